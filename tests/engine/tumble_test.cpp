// The `tumble` scene (box 1×2×3 spun near its middle axis, 3.5e-6 from the separatrix) run by
// the World with every integrator, against the odeint reference at tolerance 1e-13.
#include <cmath>

#include "tumble_reference/free_rigid_body.hpp"
#include "world_fixture.hpp"

namespace tumble {
namespace {

struct TumbleRun {
  double angle = 0.0;            // geodesic error of R at 20 s, rad
  double energy_relative = 0.0;  // |E − E0| / E0 at 20 s
  double momentum_relative = 0.0;// | |L| − |L0| | / |L0|
};

TumbleRun run_tumble(Integrator integrator, double dt, double duration = 20.0) {
  Scene scene = load_scene("tumble");
  scene.world.integrator = integrator;
  scene.world.dt = dt;
  World world(scene);
  const Body& b = world.body(0);
  const BodyState s0 = b.s;
  const double e0 = kinetic_energy(s0, b.c);
  const long steps = std::lround(duration / dt);
  for (long i = 0; i < steps; ++i) world.step();
  const Mat3 reference = tumble_reference::free_rigid_body_attitude(b.c.inertia, s0.R, s0.L,
                                                                    world.time());
  TumbleRun r;
  r.angle = rotation_angle_between(reference, b.s.R);
  r.energy_relative = std::abs(kinetic_energy(b.s, b.c) / e0 - 1.0);
  r.momentum_relative = std::abs(b.s.L.norm() / s0.L.norm() - 1.0);
  return r;
}

// `exact` meets 1e-8 rad over 20 s at dt = 1/30 (it measures 1e-11; the two reference methods
// agree to ~1e-13, see free_rotation_test). |L| is conserved exactly by every integrator here
// (none applies a torque), energy by the geometric ones to round-off or a bounded error.
TEST(TumbleScene, ExactMeetsOneNanoradianScaleBoundAtDt30) {
  const TumbleRun r = run_tumble(Integrator::exact, 1.0 / 30.0);
  EXPECT_LT(r.angle, 1e-8);
  EXPECT_LT(r.energy_relative, 1e-12);
  EXPECT_LT(r.momentum_relative, 1e-14);
  std::cout << "[ measured ] tumble exact dt=1/30: " << r.angle << " rad, energy "
            << r.energy_relative << "\n";
}

// Every other integrator converges at its order: the error at dt/2 is 2^p times smaller.
// Checked over the first 2 s, before the flip: across the separatrix a first-order method's
// phase error saturates (Euler at dt = 1/3840 is already 1.7 rad off at 20 s), so 20 s
// is not in the asymptotic range for every method.
class TumbleOrder : public ::testing::TestWithParam<Integrator> {};
TEST_P(TumbleOrder, ConvergesAtItsOrder) {
  const Integrator integrator = GetParam();
  const int order = integrator == Integrator::rk4 ? 4
                    : integrator == Integrator::midpoint || integrator == Integrator::splitting ? 2
                                                                                              : 1;
  const double dt = order == 1 ? 1.0 / 960.0 : order == 2 ? 1.0 / 120.0 : 1.0 / 60.0;
  const TumbleRun coarse = run_tumble(integrator, dt, 2.0);
  const TumbleRun fine = run_tumble(integrator, dt / 2.0, 2.0);
  std::cout << "[ measured ] tumble " << to_string(integrator) << ": dt=" << dt << " → "
            << coarse.angle << " rad, dt/2 → " << fine.angle << " rad (ratio "
            << coarse.angle / fine.angle << ")\n";
  EXPECT_NEAR(std::log2(coarse.angle / fine.angle), order, 0.35) << to_string(integrator);
  EXPECT_LT(coarse.momentum_relative, 1e-12);
}
INSTANTIATE_TEST_SUITE_P(Integrators, TumbleOrder,
                         ::testing::Values(Integrator::euler, Integrator::midpoint,
                                           Integrator::rk4, Integrator::symplectic_euler,
                                           Integrator::splitting),
                         [](const auto& info) { return std::string(to_string(info.param)); });

// At the seed's dt = 1/30 the non-exact integrators are far from the reference: print the
// error each buys (the benchmark's work-precision plot has the full curves).
TEST(TumbleScene, ErrorPerIntegratorAtDt30IsOrdered) {
  double previous = 0.0;
  for (Integrator i : {Integrator::exact, Integrator::rk4}) {
    const TumbleRun r = run_tumble(i, 1.0 / 30.0);
    std::cout << "[ measured ] tumble " << to_string(i) << " dt=1/30: " << r.angle << " rad\n";
    EXPECT_GE(r.angle, previous);
    previous = r.angle;
  }
}

}  // namespace
}  // namespace tumble
