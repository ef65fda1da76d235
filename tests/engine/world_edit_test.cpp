// World::add_body (a body added to a running world) and World::contacts (what the last step
// touched), the two calls viewers and the server's timeline build on.
#include <algorithm>
#include <cstring>

#include "world_fixture.hpp"

namespace tumble {
namespace {

/// A 1 kg unit cube named `name` at `position`, spinning a little.
BodyDef falling_cube(const std::string& name, const Vec3& position) {
  BodyDef b;
  b.name = name;
  b.position = position;
  b.angular_velocity = Vec3(0.3, -0.2, 0.5);
  return b;
}

bool same_states(const World& a, const World& b) {
  if (a.bodies().size() != b.bodies().size()) return false;
  for (std::size_t i = 0; i < a.bodies().size(); ++i)
    if (std::memcmp(&a.bodies()[i].s, &b.bodies()[i].s, sizeof(BodyState)) != 0) return false;
  return true;
}

// Added before the first step, a body gives the world built with it, bit for bit; added
// mid-run to two copies, it gives the same run in both.
TEST(AddBody, IsTheSameAsBuildingTheWorldWithItAndDeterministic) {
  Scene scene = load_scene("tower");
  const BodyDef extra = falling_cube("extra", Vec3(3.0, 4.0, 0.0));
  Scene with = scene;
  with.bodies.push_back(extra);
  World built(with), added(scene);
  EXPECT_EQ(added.add_body(extra), scene.bodies.size());
  for (int i = 0; i < 240; ++i) built.step(), added.step();
  EXPECT_TRUE(same_states(built, added));
  EXPECT_EQ(added.scene().bodies.size(), with.bodies.size());

  World a(scene);
  for (int i = 0; i < 60; ++i) a.step();
  World b = a;
  const std::uint64_t steps = a.step_count();
  a.add_body(falling_cube("late", Vec3(0.0, 14.0, 0.0)));  // lands on the tower's top
  b.add_body(falling_cube("late", Vec3(0.0, 14.0, 0.0)));
  EXPECT_EQ(a.step_count(), steps);
  for (int i = 0; i < 240; ++i) a.step(), b.step();
  EXPECT_TRUE(same_states(a, b));
  const Body& late = a.body(static_cast<BodyId>(scene.bodies.size()));
  EXPECT_NEAR(late.s.x.y(), 10.5, 0.01);  // on the tenth box, whose top is at 10 m
}

TEST(AddBody, RefusesBadDefinitionsNamingTheFieldAndChangesNothing) {
  World world(load_scene("tower"));
  const std::size_t n = world.bodies().size();
  BodyDef bad = falling_cube("bad", Vec3(0, 20, 0));
  bad.mass = -1.0;
  try {
    world.add_body(bad);
    FAIL() << "a negative mass was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("bodies[" + std::to_string(n) + "].mass"),
              std::string::npos)
        << e.what();
  }
  BodyDef twin = falling_cube(world.scene().bodies[0].name, Vec3(0, 20, 0));
  EXPECT_THROW(world.add_body(twin), InvalidInput);
  EXPECT_EQ(world.bodies().size(), n);
  EXPECT_EQ(world.scene().bodies.size(), n);
}

// The tower's contacts while it settles: every point pushes (impulse ≥ 0) along a unit normal,
// and the floor's points carry the whole tower's weight over the step (to 1e-3: it is still
// settling, 20 steps after it was placed).
TEST(Contacts, TowerPointsCarryTheWeightAboveThem) {
  World world(load_scene("tower"));
  for (int i = 0; i < 20; ++i) world.step();
  ASSERT_GT(world.awake_count(), 0u);
  std::vector<ContactView> points;
  world.contacts(points);
  ASSERT_FALSE(points.empty());
  const double g_dt = world.settings().gravity.norm() * world.settings().dt;
  double total_mass = 0.0;
  for (const Body& b : world.bodies()) total_mass += b.c.mass;
  double on_floor = 0.0;
  for (const ContactView& p : points) {
    EXPECT_TRUE(p.solved);
    EXPECT_GE(p.impulse, 0.0);
    EXPECT_NEAR(p.normal.norm(), 1.0, 1e-12);
    if (p.a != kFloorBody) continue;
    on_floor += p.impulse;
    EXPECT_NEAR(p.position.y(), 0.0, 1e-6);
  }
  EXPECT_NEAR(on_floor, total_mass * g_dt, 1e-3 * total_mass * g_dt);
}

// A box resting alone on the floor (asleep from the start) shows its four bottom corners,
// each with a quarter of its weight over a step.
TEST(Contacts, ABoxRestingAloneShowsItsFourCorners) {
  World world(load_scene("resting"));
  world.step();
  std::vector<ContactView> points;
  world.contacts(points);
  ASSERT_GE(world.bodies().size(), 1u);
  const Body& b = world.body(0);
  std::size_t corners = 0;
  for (const ContactView& p : points) {
    if (p.b != 0) continue;
    ++corners;
    EXPECT_EQ(p.a, kFloorBody);
    EXPECT_FALSE(p.solved);
    EXPECT_NEAR(p.impulse, b.c.mass * world.settings().gravity.norm() * world.settings().dt / 4,
                1e-12);
  }
  EXPECT_EQ(corners, 4u);
}

}  // namespace
}  // namespace tumble
