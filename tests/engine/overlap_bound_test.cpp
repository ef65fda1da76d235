// WorldDef::max_overlap: the exact box depth it measures, and steps that keep it (passes taken
// again in halves where a box sank deeper), the same on any thread count.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>

#include "box_box.hpp"
#include "world_fixture.hpp"

namespace tumble {
namespace {

BodyState pose(const Vec3& x, const Quat& q) {
  BodyState s;
  s.x = x;
  s.R = q.toRotationMatrix();
  return s;
}

/// The 15 axes' least overlap, computed in the world frame from the axes themselves.
double depth_by_axes(const BodyState& a, const Vec3& ha, const BodyState& b, const Vec3& hb) {
  double depth = INFINITY;
  auto along = [&](Vec3 n) {
    if (n.norm() < 1e-6) return;
    n.normalize();
    const double ra = (a.R.transpose() * n).cwiseAbs().dot(ha);
    const double rb = (b.R.transpose() * n).cwiseAbs().dot(hb);
    depth = std::min(depth, ra + rb - std::abs((b.x - a.x).dot(n)));
  };
  for (int i = 0; i < 3; ++i) {
    along(a.R.col(i));
    along(b.R.col(i));
    for (int j = 0; j < 3; ++j) along(a.R.col(i).cross(b.R.col(j)));
  }
  return depth;
}

TEST(BoxDepth, IsTheLeastOverlapOverTheFifteenAxes) {
  BodyDef small, long_one;
  small.size = {0.4, 0.6, 0.8};
  long_one.size = {2.0, 0.3, 0.5};
  const BodyConstants ca = make_body_constants(small, 0.0, 0.0);
  const BodyConstants cb = make_body_constants(long_one, 0.0, 0.0);
  // Face on face, 0.1 m deep: the depth a face axis gives.
  EXPECT_NEAR(box_depth(pose({0, 0, 0}, Quat::Identity()), ca,
                        pose({0, 0.35, 0}, Quat::Identity()), cb, -INFINITY),
              0.1, 1e-15);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int overlapping = 0;
  for (int k = 0; k < 2000; ++k) {
    const BodyState a = pose({u(rng), u(rng), u(rng)}, Quat::UnitRandom());
    const BodyState b = pose(a.x + 0.8 * Vec3{u(rng), u(rng), u(rng)}, Quat::UnitRandom());
    const double expected = depth_by_axes(a, ca.half_extents, b, cb.half_extents);
    const double depth = box_depth(a, ca, b, cb, -INFINITY);
    ASSERT_NEAR(depth, expected, 1e-12) << k;
    overlapping += depth > 0.0;
    // Asked only whether it is deeper than some depth, it may stop at an axis at or below it.
    const double stopped = box_depth(a, ca, b, cb, 0.05);
    if (expected > 0.05) ASSERT_NEAR(stopped, expected, 1e-12) << k;
    else ASSERT_LE(stopped, 0.05) << k;
  }
  EXPECT_GT(overlapping, 200);  // the draws test overlapping boxes, not only apart ones
}

/// Deepest overlap (m) of any two boxes, or of a box in the floor.
double deepest(const World& w) {
  double d = 0.0;
  const auto b = w.bodies();
  for (std::size_t i = 0; i < b.size(); ++i) {
    d = std::max(d, -(b[i].s.x.y() - b[i].s.R.row(1).cwiseAbs().dot(b[i].c.half_extents)));
    for (std::size_t j = i + 1; j < b.size(); ++j)
      d = std::max(d, box_depth(b[i].s, b[i].c, b[j].s, b[j].c, -INFINITY));
  }
  return d;
}

TEST(MaxOverlap, FallingBoxesNeverSinkDeeperThanTheBound) {
  for (const auto& [speed, spin] : {std::pair{10.0, 10.0}, {20.0, 0.0}, {10.0, 30.0}}) {
    World plain(testing::falling_boxes(speed, spin, 0.0));
    World bounded(testing::falling_boxes(speed, spin, 0.01));
    double plain_deepest = 0.0;
    std::uint64_t passes = 0, halved = 0, impacts = 0;
    for (int i = 0; i < 120; ++i) {
      plain.step();
      bounded.step();
      plain_deepest = std::max(plain_deepest, deepest(plain));
      ASSERT_LE(deepest(bounded), 0.01) << "speed " << speed << " spin " << spin << " step " << i;
      passes += bounded.last_step().passes;
      halved += bounded.last_step().halved_passes;
      impacts += bounded.last_step().impacts;  // the kept passes' only
      EXPECT_EQ(plain.last_step().passes, 1u);
    }
    // The scene does sink at dt = 1/60 without the bound, and the bound took more passes.
    EXPECT_GT(plain_deepest, 0.03) << "speed " << speed << " spin " << spin;
    EXPECT_GT(halved, 0u);
    EXPECT_GT(passes, 120u + halved);
    EXPECT_EQ(impacts, bounded.total_impacts());
    EXPECT_NEAR(bounded.time(), plain.time(), 1e-12);
    EXPECT_EQ(bounded.step_count(), 120u);
  }
}

void expect_same_bits(const World& a, const World& b);

TEST(MaxOverlap, AWorldWithoutPairsStepsAsWithoutTheBound) {
  // A box apart from others meets only the floor, at its time of impact: nothing to
  // check, nothing kept, every step one pass with the bits of the world without the bound.
  Scene bounce = testing::bundled("bounce");
  World plain(bounce);
  bounce.world.max_overlap = kMinMaxOverlap;
  World bounded(bounce);
  for (int i = 0; i < 300; ++i) {
    plain.step();
    bounded.step();
    ASSERT_EQ(bounded.last_step().passes, 1u) << "step " << i;
  }
  EXPECT_GT(bounded.total_impacts(), 3u);
  expect_same_bits(plain, bounded);
}

TEST(MaxOverlap, BoxesPlacedInsideEachOtherDoNotKeepItHalving) {
  // A scene may place boxes deeper than the bound; they are pushed apart, and a pass only
  // counts against the bound where they sink a quarter of it further.
  Scene s;
  s.world.max_overlap = 0.01;
  s.world.floor = Floor{0.0, 0.0, 0.5};
  for (int k = 0; k < 4; ++k) {
    BodyDef b;
    b.name = "box" + std::to_string(k);
    b.position = {0.0, 0.5 + 0.95 * k, 0.0};  // each 5 cm inside the one below
    b.mass = k == 3 ? 50.0 : 1.0;              // a heavy one on top
    s.bodies.push_back(b);
  }
  World w(s);
  // The first steps push the stack apart (the bottom box some centimetres into the floor) and
  // take up to 32 passes; once the halvings have wound down, the pairs still deeper than the
  // bound (up to 3 cm, their depth moving by millimetres as they part) take one pass a step.
  for (int i = 0; i < 240; ++i) {
    w.step();
    if (i >= 10) ASSERT_EQ(w.last_step().passes, 1u) << "step " << i;
  }
  EXPECT_LT(deepest(w), 0.01);  // and they did part
}

void expect_same_bits(const World& a, const World& b) {
  ASSERT_EQ(a.bodies().size(), b.bodies().size());
  for (std::size_t i = 0; i < a.bodies().size(); ++i) {
    const BodyState& x = a.bodies()[i].s;
    const BodyState& y = b.bodies()[i].s;
    ASSERT_EQ(std::memcmp(x.x.data(), y.x.data(), sizeof(double) * 3), 0) << "x of body " << i;
    ASSERT_EQ(std::memcmp(x.R.data(), y.R.data(), sizeof(double) * 9), 0) << "R of body " << i;
    ASSERT_EQ(std::memcmp(x.P.data(), y.P.data(), sizeof(double) * 3), 0) << "P of body " << i;
    ASSERT_EQ(std::memcmp(x.L.data(), y.L.data(), sizeof(double) * 3), 0) << "L of body " << i;
  }
}

TEST(MaxOverlap, TheSameBitsOnTwoThreadsAndInACopy) {
  Scene pile = testing::bundled("pile");
  pile.world.max_overlap = 0.01;
  World one(pile), two(pile);
  two.set_threads(2);
  std::uint32_t halved = 0;
  for (int i = 0; i < 45; ++i) {
    one.step();
    two.step();
    halved += one.last_step().halved_passes;
    ASSERT_EQ(one.last_step().passes, two.last_step().passes) << "step " << i;
  }
  EXPECT_GT(halved, 0u);  // the landing pile needed halves by then
  expect_same_bits(one, two);
  // A copy taken mid-run starts its next step halved as the original does.
  World copy(one);
  for (int i = 0; i < 5; ++i) {
    one.step();
    copy.step();
    ASSERT_EQ(one.last_step().passes, copy.last_step().passes) << "step " << i;
  }
  expect_same_bits(one, copy);
}

}  // namespace
}  // namespace tumble
