// Box–box contact: the narrow phase, impacts (momentum and energy), stacks (tower, pyramid,
// 100:1), dominoes, islands that sleep and wake together, determinism with many contacts.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "../sanitized.hpp"
#include "box_box.hpp"
#include "box_distance.hpp"
#include "world_fixture.hpp"

namespace tumble {
namespace {

using testing::world_from_json;

/// Deepest penetration (m, ≥ 0) between any two bodies and between any body and the floor.
double deepest_penetration(const World& world) {
  double deepest = 0.0;
  const auto bodies = world.bodies();
  const double floor_y = world.settings().floor ? world.settings().floor->height : -INFINITY;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    const Body& a = bodies[i];
    deepest = std::max(deepest, floor_y - (a.s.x.y() - a.s.R.row(1).cwiseAbs().dot(a.c.half_extents)));
    for (std::size_t j = i + 1; j < bodies.size(); ++j) {
      const Body& b = bodies[j];
      if ((a.s.x - b.s.x).norm() > a.c.bounding_radius + b.c.bounding_radius) continue;
      const BoxManifold m = collide_boxes(a.s, a.c, b.s, b.c, 0.0);
      for (int k = 0; k < m.count; ++k) deepest = std::max(deepest, -m.points[k].separation);
    }
  }
  return deepest;
}

double largest_displacement(const World& world, const std::vector<Vec3>& start) {
  double d = 0.0;
  for (std::size_t i = 0; i < start.size(); ++i)
    d = std::max(d, (world.bodies()[i].s.x - start[i]).norm());
  return d;
}

std::vector<Vec3> positions(const World& world) {
  std::vector<Vec3> x;
  for (const Body& b : world.bodies()) x.push_back(b.s.x);
  return x;
}

BodyState at(const Vec3& x, const Mat3& R = Mat3::Identity()) {
  BodyState s;
  s.x = x;
  s.R = R;
  return s;
}

// ---- narrow phase -------------------------------------------------------------------------

TEST(BoxBox, FaceOnFaceGivesFourPointsAtTheRightDepth) {
  const BodyConstants c = make_body_constants(BodyDef{}, 0.0, 0.0);
  const BoxManifold m = collide_boxes(at({0, 0, 0}), c, at({0.2, 0.99, 0.1}), c, 0.0);
  ASSERT_EQ(m.count, 4);
  EXPECT_LT((m.normal - Vec3::UnitY()).norm(), 1e-15);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(m.points[i].separation, -0.01, 1e-15);
    EXPECT_NEAR(m.points[i].position.y(), 0.495, 1e-15);
    // The overlap of the two faces: x ∈ [−0.3, 0.5], z ∈ [−0.4, 0.5].
    EXPECT_GE(m.points[i].position.x(), -0.3 - 1e-4);
    EXPECT_LE(m.points[i].position.z(), 0.5 + 1e-4);
  }
}

TEST(BoxBox, SeparatedBeyondMarginGivesNothingWithinMarginGivesSpeculativePoints) {
  const BodyConstants c = make_body_constants(BodyDef{}, 0.0, 0.0);
  EXPECT_EQ(collide_boxes(at({0, 0, 0}), c, at({1.05, 0, 0}), c, 0.02).count, 0);
  const BoxManifold m = collide_boxes(at({0, 0, 0}), c, at({1.01, 0, 0}), c, 0.02);
  ASSERT_EQ(m.count, 4);
  EXPECT_NEAR(m.points[0].separation, 0.01, 1e-14);
  EXPECT_LT((m.normal - Vec3::UnitX()).norm(), 1e-15);
}

// Two cubes turned so that a corner of each points at the other along x, 0.2 m apart: the best
// separating axis is a face normal 55° off x, along which the gap is only 0.12 m and the
// faces' clipping keeps nothing (the other cube lies beside the face). The manifold is then
// one point on the line between the nearest corners, at their distance.
TEST(BoxBox, CornersBesideTheFacesMeetAlongTheirGap) {
  const BodyConstants c = make_body_constants(BodyDef{}, 0.0, 0.0);
  const Mat3 R = Eigen::Quaterniond::FromTwoVectors(Vec3(1, 1, 1), Vec3(1, 0, 0)).toRotationMatrix();
  const double gap = 0.2, d = std::sqrt(3.0) + gap;
  const BoxManifold m = collide_boxes(at({0, 0, 0}, R), c, at({d, 0, 0}, R), c, 0.3);
  ASSERT_EQ(m.count, 1);
  EXPECT_LT((m.normal - Vec3::UnitX()).norm(), 1e-12);
  EXPECT_NEAR(m.points[0].separation, gap, 1e-12);
  EXPECT_LT((m.points[0].position - Vec3(0.5 * d, 0, 0)).norm(), 1e-12);
  EXPECT_NEAR(box_nearest(at({0, 0, 0}, R), c, at({d, 0, 0}, R), c).distance, gap, 1e-12);
  // Beyond the margin: nothing.
  EXPECT_EQ(collide_boxes(at({0, 0, 0}, R), c, at({d + 0.2, 0, 0}, R), c, 0.3).count, 0);
}

TEST(BoxBox, CrossedEdgesMeetAtOnePoint) {
  // Two cubes turned 45° about x and about z, stacked so their edges cross at the origin.
  const BodyConstants c = make_body_constants(BodyDef{}, 0.0, 0.0);
  const double r = std::sqrt(0.5);
  const Mat3 Ra = axis_rotation(0, M_PI / 4), Rb = axis_rotation(2, M_PI / 4);
  const BoxManifold m = collide_boxes(at({0, -r + 0.001, 0}, Ra), c, at({0, r - 0.001, 0}, Rb), c, 0.0);
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR(m.points[0].separation, -0.002, 1e-12);
  EXPECT_LT(m.points[0].position.norm(), 1e-12);
  EXPECT_NEAR(std::abs(m.normal.y()), 1.0, 1e-12);
}

// ---- impacts -------------------------------------------------------------------------------

/// Two cubes (masses m1, m2) on the x axis, the first moving at v toward the second at rest;
/// no gravity, no floor.
World head_on(double m1, double m2, double v, double e) {
  const std::string json = R"({"floor": null, "gravity": [0,0,0], "dt": 0.0166666666666667,
      "bodies": [{"name": "a", "mass": )" + std::to_string(m1) + R"(, "position": [-1.5, 0, 0],
                  "velocity": [)" + std::to_string(v) + R"(, 0, 0], "restitution": )" +
                          std::to_string(e) + R"(},
                 {"name": "b", "mass": )" + std::to_string(m2) + R"(, "position": [1.5, 0, 0],
                  "restitution": )" + std::to_string(e) + "}]}";
  return world_from_json(json);
}

TEST(Impact, HeadOnElasticConservesMomentumAndEnergyToRoundOff) {
  for (const double m2 : {1.0, 3.0}) {
    World world = head_on(1.0, m2, 2.0, 1.0);
    const Vec3 p0 = world.body(0).s.P + world.body(1).s.P;
    const double e0 = world.total_energy();
    for (int i = 0; i < 120; ++i) world.step();
    ASSERT_GE(world.total_impacts(), 1u);
    const Vec3 p1 = world.body(0).s.P + world.body(1).s.P;
    const double energy_error = std::abs(world.total_energy() / e0 - 1.0);
    const double momentum_error = (p1 - p0).norm() / p0.norm();
    EXPECT_LE(energy_error, 1e-14) << "m2 = " << m2;
    EXPECT_LE(momentum_error, 1e-15) << "m2 = " << m2;
    // 1D elastic collision: v1' = (m1 − m2)/(m1 + m2) v, v2' = 2 m1/(m1 + m2) v.
    EXPECT_NEAR(world.body(0).s.P.x(), (1.0 - m2) / (1.0 + m2) * 2.0, 1e-13);
    EXPECT_NEAR(world.body(1).s.P.x() / m2, 2.0 / (1.0 + m2) * 2.0, 1e-13);
    EXPECT_LT(world.body(0).s.L.norm() + world.body(1).s.L.norm(), 1e-13);  // no spin
    std::cout << "[ measured ] head-on e = 1, m2/m1 = " << m2 << ": relative energy error "
              << energy_error << ", relative momentum error " << momentum_error << "\n";
  }
}

TEST(Impact, HeadOnInelasticMovesOnTogether) {
  World world = head_on(1.0, 3.0, 2.0, 0.0);
  for (int i = 0; i < 120; ++i) world.step();
  const double v_common = 2.0 / 4.0;  // momentum 2 kg·m/s over 4 kg
  EXPECT_NEAR(world.body(0).s.P.x(), v_common, 1e-13);
  EXPECT_NEAR(world.body(1).s.P.x() / 3.0, v_common, 1e-13);
  EXPECT_NEAR((world.body(0).s.P + world.body(1).s.P).x(), 2.0, 1e-14);
  // Touching (within the speculative gap), never inside each other.
  const double gap = world.body(1).s.x.x() - world.body(0).s.x.x() - 1.0;
  EXPECT_GE(gap, 0.0);
  EXPECT_LT(gap, 2.0 / 60.0 + 1e-12);
}

/// A JSON orientation that turns a cube's corner (1, 1, 1)/2 to point along +x.
std::string corner_along_x() {
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Vec3(1, 1, 1), Vec3(1, 0, 0));
  char text[128];
  std::snprintf(text, sizeof text, "[%.17g, %.17g, %.17g, %.17g]", q.w(), q.x(), q.y(), q.z());
  return text;
}

/// Two unit cubes at x = ∓half_gap flying at each other at 20 m/s each (no gravity, no floor,
/// dt 1/60), with the given JSON orientations.
World cubes_flying_at_each_other(double half_gap, const std::string& orientation_a,
                                 const std::string& orientation_b) {
  const std::string x = std::to_string(half_gap);
  return world_from_json(
      R"({"floor": null, "gravity": [0,0,0], "dt": 0.0166666666666667, "bodies": [
        {"name": "a", "position": [-)" + x + R"(, 0, 0], "velocity": [20, 0, 0],
         "orientation": )" + orientation_a + R"(},
        {"name": "b", "position": [)" + x + R"(, 0, 0], "velocity": [-20, 0, 0],
         "orientation": )" + orientation_b + "}]}");
}

/// The deepest overlap of bodies 0 and 1 (m, ≥ 0) after each of `steps` steps, by the exact
/// box–box test.
double deepest_overlap_while_stepping(World& world, int steps) {
  double deepest = 0.0;
  for (int i = 0; i < steps; ++i) {
    world.step();
    const Body& a = world.body(0);
    const Body& b = world.body(1);
    const BoxManifold m = collide_boxes(a.s, a.c, b.s, b.c, 0.0);
    for (int k = 0; k < m.count; ++k) deepest = std::max(deepest, -m.points[k].separation);
  }
  return deepest;
}

// A cube flying corner first at another's face at 40 m/s relative (0.67 m a step at 60 Hz):
// one step starts with their bounding spheres 25 cm apart, beyond the 2 cm speculative
// distance, and the corner would end that step 3 cm inside the face. The narrow phase keeps
// a pair while its spheres are apart by less than what it closes in the step, so the
// speculative contact stops the corner at the face.
TEST(Impact, FastCornerStopsAtTheFaceItFliesAt) {
  World world = cubes_flying_at_each_other(1.0, corner_along_x(), "[1, 0, 0, 0]");
  const double deepest = deepest_overlap_while_stepping(world, 30);
  EXPECT_LT(world.body(0).s.P.x() * world.body(0).c.inv_mass, 19.0) << "the cubes never met";
  EXPECT_LT(world.body(0).s.x.x(), world.body(1).s.x.x()) << "passed through each other";
  EXPECT_LT(deepest, 1e-3) << "the corner went 1 mm or more into the face";
  std::cout << "[ measured ] corner at a face at 40 m/s: deepest overlap " << deepest << " m\n";
}

// Two cubes flying corner against corner at 40 m/s relative: no face or edge-pair axis points
// along the gap between the corners, and the faces' clipping keeps no point (each cube lies
// beside the other's faces), so the speculative contact is taken along the line between the
// nearest corners (box_box.cpp, nearest_points_contact). Without it the pair had no contact
// until the corners were 23 cm inside each other.
TEST(Impact, FastCornersAgainstCornersDoNotSinkIntoEachOther) {
  World world = cubes_flying_at_each_other(5.0 / 3.0, corner_along_x(), corner_along_x());
  const double deepest = deepest_overlap_while_stepping(world, 60);
  EXPECT_LT(world.body(0).s.P.x() * world.body(0).c.inv_mass, 19.0) << "the cubes never met";
  EXPECT_LT(deepest, 1e-3) << "the corners went 1 mm or more into each other";
  std::cout << "[ measured ] corners against corners at 40 m/s: deepest overlap " << deepest
            << " m\n";
}

// ---- stacks --------------------------------------------------------------------------------

// The tower of 10 kept awake (a zero impulse every 0.25 s stops it from sleeping) for 60 s of
// sim time: no body drifts more than 1 mm or ever penetrates more than 1 mm.
TEST(Stack, TowerOfTenStandsSixtySeconds) {
  World world(load_scene("tower"));
  const std::vector<Vec3> start = positions(world);
  double deepest = 0.0;
  for (int i = 1; i <= 3600; ++i) {
    if (i % 15 == 0) world.apply_impulse(0, Vec3::Zero());
    world.step();
    deepest = std::max(deepest, deepest_penetration(world));
  }
  EXPECT_EQ(world.awake_count(), 10u);
  const double drift = largest_displacement(world, start);
  EXPECT_LE(drift, 1e-3);
  EXPECT_LE(deepest, 1e-3);
  std::cout << "[ measured ] tower of 10 awake for 60 s: largest drift " << drift
            << " m, deepest penetration " << deepest << " m\n";
}

TEST(Stack, TowerSleepsAsOneIslandAndAFallingBoxWakesIt) {
  Scene scene = load_scene("tower");
  BodyDef extra;
  extra.name = "dropped";
  extra.position = Vec3(0.2, 30.0, 0.0);  // lands after about 2 s
  scene.bodies.push_back(extra);
  World world(scene);
  for (int i = 0; i < 60; ++i) world.step();
  for (BodyId id = 0; id < 10; ++id) EXPECT_EQ(world.body(id).activity, Activity::asleep);
  EXPECT_EQ(world.body(10).activity, Activity::awake);
  const BodyState bottom = world.body(0).s;
  int woke_at = -1;
  for (int i = 0; i < 180 && woke_at < 0; ++i) {
    world.step();
    if (world.body(0).activity == Activity::awake) woke_at = i;
  }
  ASSERT_GE(woke_at, 0) << "the falling box should wake the whole tower through its top box";
  EXPECT_GT(world.last_step().solver_bodies, 10u);
  // The hit tower rocks for seconds (a slender column loses little energy per rock: Housner
  // 1963), and when it settles is chaotic: all asleep at 10.4 s of simulated time in one
  // build, at 12.2 s after a change of rounding in a cube's ω. The wait allows about 16 s.
  for (int i = 0; i < 900; ++i) world.step();
  EXPECT_EQ(world.awake_count(), 0u);  // everything asleep again
  // A 1 kg box landing at 24 m/s shakes the tower but it stays standing.
  EXPECT_LT((world.body(0).s.x - bottom.x).norm(), 1e-2);
  for (const Body& b : world.bodies()) EXPECT_GT(b.s.R(1, 1), 0.99);
  EXPECT_LE(deepest_penetration(world), 1e-3);
}

TEST(Stack, PyramidOfTwoHundredTenFallsAsleepStanding) {
  World world(load_scene("pyramid"));
  ASSERT_EQ(world.bodies().size(), 210u);
  const std::vector<Vec3> start = positions(world);
  double asleep_at = -1.0;
  for (int i = 0; i < 600 && asleep_at < 0.0; ++i) {
    world.step();
    if (world.awake_count() == 0) asleep_at = world.time();
  }
  ASSERT_GT(asleep_at, 0.0);
  EXPECT_LE(asleep_at, 3.0);
  const double drift = largest_displacement(world, start);
  EXPECT_LE(drift, 0.02);
  EXPECT_LE(deepest_penetration(world), 1e-3);
  for (const Body& b : world.bodies()) EXPECT_GT(b.s.R(1, 1), 0.999);  // all upright
  std::cout << "[ measured ] pyramid (210 boxes) asleep at " << asleep_at
            << " s, largest displacement " << drift << " m\n";
}

// Shock propagation solves a box's supports together. One after the other, each pushed the
// box up at one side and tipped it, the next pushed the other side up further, and the box
// left faster than its supports: up the 100 rows of pyramid_large the tops of the first step
// flew up at 0.7 m/s.
TEST(Stack, ShockPropagationThrowsNothingUpATallPyramid) {
  World world(load_scene("pyramid_large"));
  ASSERT_EQ(world.bodies().size(), 5050u);
  for (int i = 0; i < 3; ++i) {
    world.step();
    double fastest_up = 0.0;
    for (const Body& b : world.bodies()) fastest_up = std::max(fastest_up, b.s.P.y() / b.c.mass);
    EXPECT_LT(fastest_up, 0.01) << "step " << i + 1;
  }
}

// The pyramid kept awake (a zero impulse on every box every 15 steps, as the contact benchmark
// does): merged support patches once met three points within µm of one line, whose nearly
// singular system the old rank bound (1e-10) inverted; a box was thrown 0.4 m.
TEST(Stack, PyramidKeptAwakeStaysPut) {
  World world(load_scene("pyramid"));
  const std::vector<Vec3> start = positions(world);
  for (int i = 0; i < 46; ++i) {
    if (i % 15 == 0)
      for (BodyId id = 0; id < world.bodies().size(); ++id) world.apply_impulse(id, Vec3::Zero());
    world.step();
  }
  EXPECT_LE(largest_displacement(world, start), 0.02);
}

// The 2-D pyramid of 5,050 unit cubes of 100 kg (base 100, 5 cm gaps, μ 0.6, dt 1/60) stands:
// its top box moves at most 5 cm, and every box is asleep within 3 s. (Too slow for the
// sanitizer builds, which skip it; the shock-propagation test above covers the same code.)
TEST(Stack, PyramidLargeStandsAndSleeps) {
  World world(load_scene("pyramid_large"));
  BodyId top = 0;
  for (BodyId id = 0; id < world.bodies().size(); ++id)
    if (world.body(id).s.x.y() > world.body(top).s.x.y()) top = id;
  const Vec3 top_start = world.body(top).s.x;
  double moved = 0.0;
  while (world.awake_count() > 0 && world.time() < 3.0) {
    world.step();
    moved = std::max(moved, (world.body(top).s.x - top_start).norm());
  }
  EXPECT_EQ(world.awake_count(), 0u) << "at " << world.time() << " s";
  EXPECT_LE(moved, 0.05);
  std::cout << "[ measured ] pyramid_large asleep at " << world.time() << " s, top box moved "
            << moved << " m\n";
}

// Any finite gravity is a valid scene, also one pointing away from the floor: a stack standing
// on the floor then falls away from it, its boxes together (they all accelerate alike, so no
// contact pushes). Shock propagation once took the floor for the body its contacts hold up:
// it read a body record at index kStaticBody (a crash under AddressSanitizer) and solved the
// floor's contacts together for a null body.
TEST(Stack, StackUnderGravityAwayFromTheFloorLeavesItTogether) {
  Scene scene;
  scene.world.gravity = {0.0, 9.81, 0.0};
  scene.world.floor = Floor{0.0, 0.0, 0.6};
  for (int i = 0; i < 3; ++i) {
    BodyDef b;
    b.name = "box" + std::to_string(i);
    b.position = {0.0, 0.5 + i, 0.0};
    scene.bodies.push_back(b);
  }
  scene.bodies.push_back(scene.bodies[0]);  // a second stack of one beside the first
  scene.bodies.back().name = "beside";
  scene.bodies.back().position.x() = 1.0;
  World world(scene);
  for (int i = 0; i < 60; ++i) world.step();
  const double t = world.time();
  for (std::size_t i = 0; i < world.bodies().size(); ++i) {
    const Body& b = world.body(static_cast<BodyId>(i));
    ASSERT_EQ(b.activity, Activity::awake) << i;
    const double y0 = i < 3 ? 0.5 + static_cast<double>(i) : 0.5;
    // Free fall upwards: ½ g t² = 4.905 m (island bodies step with their end-of-step velocity,
    // a g t dt / 2 = 0.08 m lead); the stack's gaps stay closed and nothing turns.
    EXPECT_NEAR(b.s.x.y() - y0, 0.5 * 9.81 * t * t, 0.1) << i;
    EXPECT_NEAR(b.s.P.y(), 9.81 * t, 1e-9) << i;
    EXPECT_LT(std::abs(b.s.x.x() - (i < 3 ? 0.0 : 1.0)) + std::abs(b.s.x.z()), 1e-12) << i;
    EXPECT_LT(b.s.L.norm(), 1e-12) << i;
  }
  for (int i = 0; i < 2; ++i)
    EXPECT_NEAR(world.body(i + 1).s.x.y() - world.body(i).s.x.y(), 1.0, 1e-9) << i;
}

TEST(Stack, HeavyOnLightHolds) {
  World world(load_scene("heavy_on_light"));
  ASSERT_NEAR(world.body(1).c.mass / world.body(0).c.mass, 100.0, 1e-12);
  const std::vector<Vec3> start = positions(world);
  double deepest = 0.0;
  for (int i = 1; i <= 1200; ++i) {
    if (i % 15 == 0) world.apply_impulse(0, Vec3::Zero());  // keep it awake
    world.step();
    deepest = std::max(deepest, deepest_penetration(world));
  }
  EXPECT_LE(largest_displacement(world, start), 1e-3);
  EXPECT_LE(deepest, 1e-3);
  std::cout << "[ measured ] 100:1 stack awake for 20 s: displacement "
            << largest_displacement(world, start) << " m, deepest penetration " << deepest
            << " m\n";
}

TEST(Dominoes, TheFirstKnocksDownTheRest) {
  World world(load_scene("dominoes"));
  for (int i = 0; i < 600; ++i) world.step();
  for (const Body& b : world.bodies()) EXPECT_LT(b.s.R(1, 1), 0.5) << "a domino still stands";
  EXPECT_LE(deepest_penetration(world), 5e-3);
}

// ---- determinism and cost ------------------------------------------------------------------

TEST(Determinism, ManyContactsGiveBitIdenticalStatesAndCopiesContinueIdentically) {
  Scene scene = load_scene("pile");
  scene.bodies.resize(300);  // three layers that land on each other
  auto run = [&scene](int steps) {
    World world(scene);
    for (int i = 0; i < steps; ++i) world.step();
    return world;
  };
  // The layers land from step ~30; a sanitizer build (10-60x slower) stops sooner.
  const int steps = testing::kSanitized ? 75 : 150, more = testing::kSanitized ? 45 : 100;
  World a = run(steps);
  World b = run(steps);
  ASSERT_GT(a.last_step().contacts, 50u);
  World c = a;  // a copy carries the contact cache and sleep groups
  for (int i = 0; i < more; ++i) a.step(), b.step(), c.step();
  for (std::size_t i = 0; i < a.bodies().size(); ++i) {
    EXPECT_EQ(std::memcmp(&a.bodies()[i].s, &b.bodies()[i].s, sizeof(BodyState)), 0) << i;
    EXPECT_EQ(std::memcmp(&a.bodies()[i].s, &c.bodies()[i].s, sizeof(BodyState)), 0) << i;
  }
}

// Steps `world` until every body sleeps, at most `steps` steps; the sim time it took, or −1.
double step_until_asleep(World& world, int steps) {
  for (int i = 0; i < steps; ++i) {
    world.step();
    if (world.awake_count() == 0) return world.time();
  }
  return -1.0;
}

TEST(Pile, ThreeHundredBoxesSettleAndSleepWithoutDeepPenetration) {
  Scene scene = load_scene("pile");
  scene.bodies.resize(300);
  World world(scene);
  const double asleep_at = step_until_asleep(world, 1800);  // 30 s at most
  EXPECT_GT(asleep_at, 0.0);
  EXPECT_EQ(world.frozen_count(), 0u);
  EXPECT_LE(deepest_penetration(world), 5e-3);
}

// A box balanced on two supports, or wedged between two boxes, rocks on its contacts like a
// pendulum, which rigid contacts do not damp: its points pass 0.05–0.15 m/s at the bottom of
// each swing while staying within millimetres. Before the sleep rule counted such a body as
// still (sleep.cpp, kSleepReach), piles of these four sizes kept an island of 28–250 boxes
// awake around one rocking box for the whole 30 s (8 of the 30 sizes from 200 to 490 did).
TEST(Pile, PilesWithABoxRockingInPlaceSleep) {
  for (std::size_t n : {200u, 260u, 290u, 320u}) {
    Scene scene = load_scene("pile");
    scene.bodies.resize(n);
    World world(scene);
    const double asleep_at = step_until_asleep(world, 1200);  // 20 s at most
    EXPECT_GT(asleep_at, 0.0) << n << " boxes: " << world.awake_count() << " still awake at 20 s";
    EXPECT_EQ(world.frozen_count(), 0u) << n;
  }
}

// Bodies that never come near each other run no narrow phase, and each moves bit for bit as
// it would alone: the floor-only path (exact flight, TOI, resting contact) is untouched.
TEST(BroadPhase, BodiesThatNeverMeetMoveExactlyAsAlone) {
  const std::string body_a = R"({"name": "a", "size": [1, 2, 3], "position": [0, 3, 0],
      "orientation": [0.9, 0.1, 0.3, 0.2], "angular_velocity": [1, 2, 0.5]})";
  const std::string body_b = R"({"name": "b", "position": [6, 2, 0], "velocity": [0, 1, 0],
      "angular_velocity": [0, 3, 1]})";
  const std::string head = R"({"floor": {"restitution": 0.5, "friction": 0.3}, "bodies": [)";
  World alone = world_from_json(head + body_a + "]}");
  World both = world_from_json(head + body_a + "," + body_b + "]}");
  for (int i = 0; i < 600; ++i) {
    alone.step();
    both.step();
    ASSERT_EQ(both.last_step().contacts, 0u);
    ASSERT_EQ(both.last_step().solver_bodies, 0u);
  }
  EXPECT_GT(alone.total_impacts(), 0u);
  EXPECT_EQ(std::memcmp(&alone.body(0).s, &both.body(0).s, sizeof(BodyState)), 0);
}

}  // namespace
}  // namespace tumble
