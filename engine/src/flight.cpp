#include <algorithm>
#include <array>
#include <atomic>

#include "floor_contact.hpp"
#include "free_rotation.hpp"
#include "lanes.hpp"
#include "integrators.hpp"
#include "pipeline.hpp"

namespace tumble {
namespace {

constexpr std::size_t kIslandGrain = 256;  // bodies per chunk: ~20 ns each
constexpr std::size_t kLoneGrain = 16;     // bodies per chunk: 0.1 µs to several each

// An island body's momenta already hold the step's gravity and contact impulses (the contact
// solve is velocity-level, Box2D's order: integrate velocities, solve, integrate positions), so
// it moves with its solved velocities: x + dt v, R turned by dt ω (semi-implicit Euler), the
// split-impulse pseudo velocities added to the positions only. The rotation is the one the
// solve's linearisation assumed (a vertex moves by dt (v + ω × r)). Measured alternative: the
// scene's torque-free rotation (`exact`: Jacobi elliptic functions) with the solved L moves
// the vertices of a general box differently from what the solve assumed; the first 300 boxes
// of `pile` then jitter and take 12.35 s to sleep instead of 4.35 s.
void fly_in_island(Body& b, const SolverBody& solved, double dt) {
  b.s.x += dt * (solved.v + solved.vp);
  const Vec3 turn = dt * (solved.w + solved.wp);
  if (!turn.isZero()) b.s.R = rotation_from_vector(turn) * b.s.R;
  b.in_contact = true;
}

// The torque-free turns over the whole step of the general boxes among lone bodies
// [begin, end) (at most kLoneGrain) under `exact`, computed together (free_rotation_exact_many:
// four at a time in SIMD lanes, the same bits as one at a time); given[k − begin] points at
// body k's, null for the others. A body's step uses it for its first whole-step flight, in the
// air or near the floor (advance_with_floor); a body that glides or rests instead leaves it.
// Measured (10,000 general boxes on the frictionless floor, whole processes, medians of seven
// interleaved pairs): the first 0.5 s in 0.67× the time, 2 s in 0.87×; near the floor too,
// 2 s in 0.91× the time of batching only the bodies clear of it.
void turn_general_boxes(StepContext& ctx, std::size_t begin, std::size_t end,
                        std::array<Mat3, kLoneGrain>& rotated,
                        std::array<const Mat3*, kLoneGrain>& given) {
  given.fill(nullptr);
  if (!kLanesInOneRegister || ctx.world.integrator != Integrator::exact) return;
  std::array<FreeFlow, kLoneGrain> flows;
  std::size_t n = 0;
  for (std::size_t k = begin; k < end; ++k) {
    const Body& b = ctx.bodies[ctx.scratch.lone_bodies[k]];
    if (b.c.shape == InertiaShape::isotropic) continue;
    flows[n++] = {&b.c.inertia, &b.s.R, &b.s.L, &rotated[k - begin]};
    given[k - begin] = &rotated[k - begin];
  }
  free_rotation_exact_many(std::span(flows.data(), n), ctx.dt);
}

}  // namespace

// Every body moves on its own, so the bodies are shared out among the pool's threads; the
// counters are integers, whose sum does not depend on the order of the chunks.
void flight(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  ctx.pool.for_each(s.solver_bodies.size(), kIslandGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      Body& b = ctx.bodies[s.solver_bodies[k]];
      fly_in_island(b, s.solver.bodies[k], ctx.dt);
      note_moved(ctx.broad, s.solver_bodies[k], b.s);
    }
  });
  // A lone body flies with the scene's integrator, its floor impacts found at their time of
  // impact and resting contact handled exactly (floor_contact.cpp). Finalize's rule and the
  // sleep rule (an island of one) follow at once, and the next broad phase's check of its
  // quiet bound, while the body is in cache: apart, each streamed the awake bodies' 288-byte
  // records again (Box2D v3's finalize pass likewise checks each body's sleep velocity and its
  // enlarged box in the pass that integrates its position).
  // Each lone body's turn is kept for the next step in the slot of its place in the list (a
  // slot that changes body is recomputed: the cache is keyed by the turn's angle alone), so
  // the memory follows the bodies in flight, 104 bytes each, not the world's size.
  if (s.spins.size() < s.lone_bodies.size()) s.spins.resize(s.lone_bodies.size());
  const bool renormalize = renormalize_after(ctx.step_index);
  std::atomic<std::uint32_t> asleep = 0;
  ctx.pool.for_each(s.lone_bodies.size(), kLoneGrain, [&](std::size_t begin, std::size_t end) {
    std::uint32_t impacts = 0, iterations = 0, frozen = 0, slept = 0;
    std::array<Mat3, kLoneGrain> rotated;
    std::array<const Mat3*, kLoneGrain> given;
    for (std::size_t block = begin; block < end; block += kLoneGrain) {
      const std::size_t stop = std::min(end, block + kLoneGrain);
      turn_general_boxes(ctx, block, stop, rotated, given);
      for (std::size_t k = block; k < stop; ++k) {
        const std::uint32_t id = s.lone_bodies[k];
        Body& b = ctx.bodies[id];
        const BodyState before = b.s;
        const FloorStepResult r =
            advance_with_floor(b, ctx.world, ctx.dt, &s.spins[k], given[k - block]);
        impacts += static_cast<std::uint32_t>(r.impacts);
        iterations += static_cast<std::uint32_t>(r.toi_iterations);
        b.in_contact = r.touched;
        if (!finalize_body(b, before, renormalize)) {
          ++frozen;
          continue;
        }
        // A body in flight is never still: its timer restarts (settle_lone_body's first rule,
        // without the call for the 80-90 % of a fall's body-steps that touch nothing).
        if (b.in_contact) slept += settle_lone_body(b, id, ctx.cache, ctx.dt, ctx.world) ? 1 : 0;
        else b.still_time = 0.0;
        note_moved(ctx.broad, id, b.s);
      }
    }
    std::atomic_ref(ctx.stats.impacts).fetch_add(impacts, std::memory_order_relaxed);
    std::atomic_ref(ctx.stats.toi_iterations).fetch_add(iterations, std::memory_order_relaxed);
    if (frozen) std::atomic_ref(ctx.stats.newly_frozen).fetch_add(frozen);
    if (slept) asleep.fetch_add(slept, std::memory_order_relaxed);
  });
  ctx.cache.activity_epoch += asleep.load();  // finalize moves it for the frozen ones
}

}  // namespace tumble
