#include "floor_contact.hpp"
#include "integrators.hpp"
#include "pipeline.hpp"

namespace tumble {
namespace {

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

}  // namespace

void flight(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  for (std::size_t k = 0; k < s.solver_bodies.size(); ++k)
    fly_in_island(ctx.bodies[s.solver_bodies[k]], s.solver.bodies[k], ctx.dt);
  // A lone body flies with the scene's integrator, its floor impacts found at their time of
  // impact and resting contact handled exactly (floor_contact.cpp).
  for (std::uint32_t id : s.lone_bodies) {
    Body& b = ctx.bodies[id];
    const FloorStepResult r = advance_with_floor(b, ctx.world, ctx.dt);
    ctx.stats.impacts += static_cast<std::uint32_t>(r.impacts);
    ctx.stats.toi_iterations += static_cast<std::uint32_t>(r.toi_iterations);
    b.in_contact = r.touched;
  }
}

}  // namespace tumble
