// World-level behaviour: impulses, sleeping and waking, determinism, finiteness, orthonormality.
#include <cmath>
#include <cstring>

#include "floor_contact.hpp"
#include "world_fixture.hpp"

namespace tumble {
namespace {

using testing::world_from_json;

TEST(Impulse, ChangesMomentaAsSeedEquationsSay) {
  World world = world_from_json(R"({"floor": null, "gravity": [0,0,0],
      "bodies": [{"name": "a", "size": [1,2,3], "mass": 2, "position": [1,2,3]}]})");
  const Vec3 J(0.5, -1.0, 2.0), p(1.5, 2.5, 2.0);
  world.apply_impulse(0, J, p);
  const Body& b = world.body(0);
  EXPECT_LT((b.s.P - J).norm(), 1e-15);
  EXPECT_LT((b.s.L - (p - Vec3(1, 2, 3)).cross(J)).norm(), 1e-15);
  world.apply_impulse(0, Vec3(1, 0, 0));  // at the centre of mass: no angular change
  EXPECT_LT((b.s.L - (p - Vec3(1, 2, 3)).cross(J)).norm(), 1e-15);
}

TEST(Impulse, RefusesBadInputAndLeavesStateAlone) {
  World world = world_from_json(R"({"bodies": [{"position": [0,3,0]}]})");
  EXPECT_THROW(world.apply_impulse(5, Vec3(1, 0, 0)), InvalidInput);
  EXPECT_THROW(world.apply_impulse(0, Vec3(NAN, 0, 0)), InvalidInput);
  EXPECT_THROW(world.apply_impulse(0, Vec3(1, 0, 0), Vec3(INFINITY, 0, 0)), InvalidInput);
  EXPECT_EQ(world.body(0).s.P, Vec3::Zero());
  BodyId id = 0;
  EXPECT_FALSE(world.find_body("nobody", id));
  EXPECT_TRUE(world.find_body("box", id));
}

// A sleeping body costs nothing: it is not integrated and its state stays bit-identical.
// An impulse wakes it.
TEST(Sleep, SleepingBodyIsSkippedUntilAnImpulseWakesIt) {
  World world(load_scene("resting"));
  for (int i = 0; i < 60; ++i) world.step();
  ASSERT_EQ(world.awake_count(), 0u);
  const BodyState before = world.body(1).s;
  for (int i = 0; i < 100; ++i) world.step();
  EXPECT_EQ(world.last_step().awake, 0u);
  EXPECT_EQ(std::memcmp(&before, &world.body(1).s, sizeof(BodyState)), 0);
  world.apply_impulse(1, Vec3(0, 20, 0));
  EXPECT_EQ(world.body(1).activity, Activity::awake);
  world.step();
  EXPECT_EQ(world.last_step().awake, 1u);
  EXPECT_GT(world.body(1).s.x.y(), before.x.y());
  for (int i = 0; i < 600; ++i) world.step();
  EXPECT_EQ(world.body(1).activity, Activity::asleep);  // lands and sleeps again
}

// Same scene, same calls: bit-identical states.
// A cube that lands flat on a floor with e = 0 stops dead on its face (P = L = 0): it is in
// static equilibrium at once and sleeps on the next step, not after the 0.5 s timer that
// tells a pause from rest. Dropped from 1 m it lands at √(2/9.81) = 0.4515 s.
TEST(Sleep, ABoxThatStopsOnAFaceSleepsAtOnce) {
  World world = world_from_json(R"({"dt": 0.004166666666666667,
      "floor": {"height": 0, "restitution": 0, "friction": 1},
      "bodies": [{"name": "cube", "position": [0, 1.5, 0]}]})");
  double asleep_at = -1.0;
  while (world.time() < 2.0 && asleep_at < 0.0) {
    world.step();
    if (world.awake_count() == 0) asleep_at = world.time();
  }
  EXPECT_GT(asleep_at, 0.4515);
  EXPECT_LT(asleep_at, 0.4515 + 3 * world.settings().dt);
  EXPECT_NEAR(world.body(0).s.x.y(), 0.5, 1e-9);
}

TEST(Determinism, SameScenesAndCallsGiveBitIdenticalStates) {
  auto run = [] {
    World world(load_scene("many"));
    for (int i = 0; i < 300; ++i) {
      if (i == 100) world.apply_impulse(7, Vec3(1, 5, -2), world.body(7).s.x + Vec3(0.1, 0.2, 0));
      world.step();
    }
    return world;
  };
  const World a = run();
  const World b = run();
  for (std::size_t i = 0; i < a.bodies().size(); ++i)
    EXPECT_EQ(std::memcmp(&a.bodies()[i].s, &b.bodies()[i].s, sizeof(BodyState)), 0) << i;
}

// A body that goes non-finite is frozen at its last finite state and reported.
TEST(Finiteness, NonFiniteBodyIsFrozenNotPassedOn) {
  World world = world_from_json(R"({"floor": null, "gravity": [0,0,0],
      "bodies": [{"name": "a", "angular_velocity": [0, 1e5, 0]}, {"name": "b", "position": [3,0,0]}]})");
  world.apply_impulse(0, Vec3(1e308, 0, 0));
  world.apply_impulse(0, Vec3(1e308, 0, 0));  // P overflows to +inf on the next step's x
  world.step(1e-3);
  world.step(1e-3);
  EXPECT_EQ(world.body(0).activity, Activity::frozen);
  EXPECT_EQ(world.frozen_count(), 1u);
  EXPECT_TRUE(all_finite(world.body(0).s.x));
  EXPECT_EQ(world.body(1).activity, Activity::awake);
  EXPECT_TRUE(std::isfinite(world.total_energy()));
  EXPECT_THROW(world.apply_impulse(0, Vec3(1, 0, 0)), InvalidInput);
}

// ‖RᵀR − I‖ stays at round-off over 10^6 steps with every integrator.
class Orthonormality : public ::testing::TestWithParam<Integrator> {};
TEST_P(Orthonormality, StaysOrthonormalOverAMillionSteps) {
  Scene scene = load_scene("tumble");
  scene.world.integrator = GetParam();
  // The general box under `exact` costs about a microsecond a step; the others are cheaper.
  World world(scene);
  for (int i = 0; i < 1000000; ++i) world.step();
  const double error = orthonormality_error(world.body(0).s.R);
  EXPECT_LE(error, 1e-12) << to_string(GetParam());
  std::cout << "[ measured ] " << to_string(GetParam()) << ": ‖RᵀR − I‖ after 1e6 steps = " << error
            << "\n";
}
INSTANTIATE_TEST_SUITE_P(AllIntegrators, Orthonormality, ::testing::ValuesIn(kIntegrators),
                         [](const auto& info) { return std::string(to_string(info.param)); });

}  // namespace
}  // namespace tumble
