// Free flight against closed forms: ballistic throws and spinning cubes.
#include <cmath>
#include <cstring>
#include <string>

#include "world_fixture.hpp"

namespace tumble {
namespace {

class FlightTest : public ::testing::TestWithParam<Integrator> {};

Scene throw_scene(Integrator integrator) {
  Scene s;
  s.world.floor.reset();
  s.world.dt = 1.0 / 30.0;
  s.world.integrator = integrator;
  BodyDef b;
  b.size = {0.5, 1.0, 2.0};
  b.mass = 3.0;
  b.position = {1.0, 10.0, -2.0};
  b.velocity = {2.0, 7.0, -1.5};
  s.bodies.push_back(b);
  return s;
}

// Under uniform gravity every integrator here is exact for x(t) = x0 + v0 t + ½ g t² when
// there is no spin, except Euler (first order) and symplectic Euler (one h² g term off).
TEST_P(FlightTest, BallisticThrowMatchesClosedForm) {
  const Integrator integrator = GetParam();
  World world(throw_scene(integrator));
  for (int i = 0; i < 90; ++i) world.step();
  const double t = world.time();
  const Vec3 g(0, -9.81, 0);
  const Vec3 expected = Vec3(1.0, 10.0, -2.0) + Vec3(2.0, 7.0, -1.5) * t + 0.5 * g * t * t;
  const double error = (world.body(0).s.x - expected).norm();
  if (integrator == Integrator::euler || integrator == Integrator::symplectic_euler) {
    // Both are off by ½ g h t per step: 0.5 · 9.81 · (1/30) · 3 s ≈ 0.49 m.
    EXPECT_NEAR(error, 0.5 * 9.81 * (1.0 / 30.0) * t, 1e-9);
  } else {
    EXPECT_LT(error, 1e-12) << to_string(integrator);
  }
  const Vec3 v = velocity(world.body(0).s, world.body(0).c);
  EXPECT_LT((v - (Vec3(2.0, 7.0, -1.5) + g * t)).norm(), 1e-12);
}

double cube_rotation_error(Integrator integrator, double dt, double duration) {
  Scene s = throw_scene(integrator);
  s.world.dt = dt;
  s.bodies[0].size = {1, 1, 1};
  s.bodies[0].angular_velocity = {0.3, -1.1, 2.0};
  s.bodies[0].orientation = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  World world(s);
  const long steps = std::lround(duration / dt);
  for (long i = 0; i < steps; ++i) world.step();
  EXPECT_LT(orthonormality_error(world.body(0).s.R), 1e-13);
  const Mat3 R0 = s.bodies[0].orientation.toRotationMatrix();
  const Mat3 expected = rotation_from_vector(world.time() * Vec3(0.3, -1.1, 2.0)) * R0;
  return rotation_angle_between(expected, world.body(0).s.R);
}

// A cube's inertia is isotropic, so ω is constant and R(t) = exp(t ω̂) R0 exactly: `exact`
// and `splitting` (which take the cube's closed form) and symplectic Euler (whose step is that
// same exponential) reproduce it to round-off; the others converge at their order (error
// ratio 2^p when dt halves).
TEST_P(FlightTest, SpinningCubeFollowsClosedFormRotation) {
  const Integrator integrator = GetParam();
  const double coarse = cube_rotation_error(integrator, 1.0 / 60.0, 10.0);
  if (integrator == Integrator::exact || integrator == Integrator::splitting ||
      integrator == Integrator::symplectic_euler) {
    EXPECT_LT(coarse, 1e-12) << to_string(integrator);
    return;
  }
  const double fine = cube_rotation_error(integrator, 1.0 / 120.0, 10.0);
  // Euler's R + h ω̂ R projected back onto SO(3) is the rotation by atan(h|ω|) about ω: for
  // a constant ω that is second order, so Euler converges like midpoint here.
  const int order = integrator == Integrator::rk4 ? 4 : 2;
  const double ratio = coarse / fine;
  EXPECT_NEAR(std::log2(ratio), order, 0.25) << to_string(integrator) << " errors " << coarse
                                              << " → " << fine;
}

// Lone general boxes under `exact` fly four at a time in SIMD lanes (flight.cpp, where the
// build has AVX): each must end with the bits it has when it is the world's only body, which
// steps it alone. Twelve boxes of different shapes and spins (a cube among them, which never
// waits for the lanes), separated on a grid, fall 2 s onto a frictionless floor with e = 0.5:
// flights, impacts found at their time and rocking on the floor, every path a turn takes.
TEST(Flight, GeneralBoxesInLanesMatchEachAlone) {
  Scene all;
  all.world.dt = 1.0 / 60.0;
  all.world.floor = Floor{0.0, 0.5, 0.0};
  for (int i = 0; i < 12; ++i) {
    BodyDef b;
    b.size = i == 5 ? Vec3(0.4, 0.4, 0.4) : Vec3(0.2 + 0.03 * i, 0.5 - 0.02 * i, 0.3 + 0.01 * i);
    b.name = "box" + std::to_string(i);
    b.mass = 1.0 + i;
    b.position = {2.0 * (i % 4), 1.0 + 0.15 * i, 2.0 * (i / 4)};
    b.orientation = Quat(Eigen::AngleAxisd(0.3 * i, Vec3(1.0, 2.0 - i, 0.5 * i).normalized()));
    b.angular_velocity = {0.5 * i - 2.0, 3.0 - 0.4 * i, 1.0 + 0.2 * i};
    all.bodies.push_back(b);
  }
  World together(all);
  for (int n = 0; n < 120; ++n) together.step();
  for (std::size_t i = 0; i < all.bodies.size(); ++i) {
    Scene one = all;
    one.bodies = {all.bodies[i]};
    World alone(one);
    for (int n = 0; n < 120; ++n) alone.step();
    const BodyState& a = alone.body(0).s;
    const BodyState& b = together.body(static_cast<BodyId>(i)).s;
    EXPECT_EQ(std::memcmp(a.R.data(), b.R.data(), sizeof(Mat3)), 0) << "body " << i;
    EXPECT_EQ(std::memcmp(a.x.data(), b.x.data(), sizeof(Vec3)), 0) << "body " << i;
    EXPECT_EQ(std::memcmp(a.L.data(), b.L.data(), sizeof(Vec3)), 0) << "body " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(AllIntegrators, FlightTest, ::testing::ValuesIn(kIntegrators),
                         [](const auto& info) { return std::string(to_string(info.param)); });

}  // namespace
}  // namespace tumble
