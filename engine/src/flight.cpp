#include <array>
#include <atomic>

#include "floor_contact.hpp"
#include "free_rotation.hpp"
#include "integrators.hpp"
#include "lanes.hpp"
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

// One lone body's step: the scene's integrator with the floor, finalize's rule, the sleep
// rule (an island of one) and the next broad phase's quiet check, while the body is in cache.
// Adds to the chunk's counters.
struct LoneStep {
  StepContext& ctx;
  bool renormalize;
  std::uint32_t impacts = 0, iterations = 0, frozen = 0, slept = 0;

  // Lone body k's step.
  void operator()(std::size_t k) {
    run(k, [&](Body& b) { return advance_with_floor(b, ctx.world, ctx.dt, &spin(k)); });
  }

  // The same, its torque-free attitude after the step, `rotated`, computed beforehand.
  void operator()(std::size_t k, const Mat3& rotated) {
    run(k, [&](Body& b) { return advance_with_floor(b, ctx.world, ctx.dt, &spin(k), rotated); });
  }

 private:
  SpinCache& spin(std::size_t k) { return ctx.scratch.spins[k]; }

  // Lone body k's step, its flight by fly(body).
  template <class Fly>
  void run(std::size_t k, const Fly& fly) {
    const std::uint32_t id = ctx.scratch.lone_bodies[k];
    Body& b = ctx.bodies[id];
    const BodyState before = b.s;
    const FloorStepResult r = fly(b);
    impacts += static_cast<std::uint32_t>(r.impacts);
    iterations += static_cast<std::uint32_t>(r.toi_iterations);
    b.in_contact = r.touched;
    if (!finalize_body(b, before, renormalize)) {
      ++frozen;
      return;
    }
    // A body in flight is never still: its timer restarts (settle_lone_body's first rule,
    // without the call for the 80-90 % of a fall's body-steps that touch nothing).
    if (b.in_contact) slept += settle_lone_body(b, id, ctx.cache, ctx.dt, ctx.world) ? 1 : 0;
    else b.still_time = 0.0;
    note_flown(ctx, id, b);
  }
};

// General boxes (three distinct moments) under `exact` held back until four are waiting,
// then turned together (free_rotation_exact_many: their elliptic-function flows in four
// SIMD lanes, the same bits as one at a time) and stepped. A body's step uses its turn for
// its first whole-step flight, in the air or near the floor (advance_with_floor); one that
// glides or rests leaves it. Each lone body's step writes only its own state and its own
// slots, so the order within a chunk changes nothing. Cubes pass straight through, and in a
// world of cubes alone (the World counts the others as they are added) nothing looks at a
// body's shape: a pass ahead over every body to pick the general ones cost 10,000 cubes 12 %
// more time (their records read twice), the look in the same pass 3–6 %. Measured (10,000
// general boxes on the frictionless floor, `World::step` timed, medians of 7 and 5
// interleaved pairs): the first 0.5 s in 0.54× the time, 2 s in 0.79×.
class GeneralBoxQueue {
 public:
  explicit GeneralBoxQueue(LoneStep& step) : step_(step) {}

  // Holds lone body k back; steps the four held once it is the fourth.
  void hold(std::size_t k) {
    held_[n_++] = k;
    if (n_ == held_.size()) flush();
  }

  // Turns and steps the bodies held.
  void flush() {
    std::array<FreeFlow, 4> flows;
    std::array<Mat3, 4> rotated;
    for (std::size_t i = 0; i < n_; ++i) {
      const Body& b = step_.ctx.bodies[step_.ctx.scratch.lone_bodies[held_[i]]];
      flows[i] = {&b.c.inertia, &b.s.R, &b.s.L, &rotated[i]};
    }
    free_rotation_exact_many(std::span(flows.data(), n_), step_.ctx.dt);
    for (std::size_t i = 0; i < n_; ++i) step_(held_[i], rotated[i]);
    n_ = 0;
  }

 private:
  LoneStep& step_;
  std::array<std::size_t, 4> held_;
  std::size_t n_ = 0;
};

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
  const bool batch =
      kLanesInOneRegister && ctx.unequal_moments && ctx.world.integrator == Integrator::exact;
  ctx.pool.for_each(s.lone_bodies.size(), kLoneGrain, [&](std::size_t begin, std::size_t end) {
    LoneStep step{ctx, renormalize};
    GeneralBoxQueue general(step);
    for (std::size_t k = begin; k < end; ++k) {
      if (batch && ctx.bodies[s.lone_bodies[k]].c.shape != InertiaShape::isotropic)
        general.hold(k);
      else
        step(k);
    }
    general.flush();
    std::atomic_ref(ctx.stats.impacts).fetch_add(step.impacts, std::memory_order_relaxed);
    std::atomic_ref(ctx.stats.toi_iterations)
        .fetch_add(step.iterations, std::memory_order_relaxed);
    if (step.frozen) std::atomic_ref(ctx.stats.newly_frozen).fetch_add(step.frozen);
    if (step.slept) asleep.fetch_add(step.slept, std::memory_order_relaxed);
  });
  ctx.cache.activity_epoch += asleep.load();  // finalize moves it for the frozen ones
}

}  // namespace tumble
