// Box–box manifolds recycled from records in the bodies' frames (manifold_record.hpp): near
// the recorded pose a recycled manifold is the fresh one, beyond kRecycleDistance none is.
#include <gtest/gtest.h>

#include "box_box.hpp"
#include "manifold_record.hpp"
#include "world_fixture.hpp"

namespace tumble {
namespace {

using testing::pose;

/// A pose of b resting on a's top face, in a's frame moved to world by (Ra, xa), with b's
/// offset (in a's frame) and turn about a's normal.
BodyState on_top(const BodyState& a, const Vec3& offset, double turn) {
  return pose(a.x + a.R * offset, a.R * axis_rotation(1, turn));
}

/// Each point of `m` against the fresh manifold's point with the same feature id.
void expect_same_points(const BoxManifold& recycled, const BoxManifold& fresh, double position,
                        double separation) {
  ASSERT_EQ(recycled.count, fresh.count);
  EXPECT_LT((recycled.normal - fresh.normal).norm(), 1e-14);
  for (int i = 0; i < recycled.count; ++i) {
    int j = 0;
    while (j < fresh.count && fresh.points[j].id != recycled.points[i].id) ++j;
    ASSERT_LT(j, fresh.count) << "point " << i << " has no fresh counterpart";
    EXPECT_LT((recycled.points[i].position - fresh.points[j].position).norm(), position);
    EXPECT_NEAR(recycled.points[i].separation, fresh.points[j].separation, separation);
  }
}

class ManifoldRecordTest : public ::testing::Test {
 protected:
  const BodyConstants c = make_body_constants(BodyDef{}, 0.0, 0.0);
  // a turned well away from the world axes, so the frames matter.
  const BodyState a = pose({0.3, 2.0, -1.0}, axis_rotation(0, 0.7) * axis_rotation(2, -0.4));
  const BodyState b = on_top(a, {0.2, 0.99, 0.1}, 0.3);
  const BoxManifold recorded = collide_boxes(a, c, b, c, 0.02);
  const ManifoldRecord record = record_manifold(recorded, a, b);

  /// The record recycled at poses (a2, b2): whether it was, and the manifold.
  bool recycle(const BodyState& a2, const BodyState& b2, BoxManifold& out) const {
    return recycle_manifold(record, a2, c.bounding_radius, b2, c.bounding_radius, out);
  }
};

TEST_F(ManifoldRecordTest, TheSameRelativePoseAnywhereGivesTheFreshManifold) {
  ASSERT_EQ(recorded.count, 4);
  // Both boxes carried by one rigid motion: the relative pose is the recorded one.
  const Mat3 turn = axis_rotation(2, 2.1) * axis_rotation(1, -1.3);
  const Vec3 shift(5.0, -3.0, 7.0);
  const BodyState a2 = pose(turn * a.x + shift, turn * a.R), b2 = pose(turn * b.x + shift, turn * b.R);
  BoxManifold m;
  ASSERT_TRUE(recycle(a2, b2, m));
  expect_same_points(m, collide_boxes(a2, c, b2, c, 0.02), 1e-14, 1e-14);
}

TEST_F(ManifoldRecordTest, ASmallerMoveThanTheDistanceKeepsExactSeparations) {
  // b sinks 0.4 mm into a and slides 0.4 mm along the face, a turn of 0.2 mrad about the
  // normal: the patch's corners move by under 0.5 mm, the face-on-face gaps stay exact.
  const BodyState b2 = on_top(a, {0.2004, 0.9896, 0.1}, 0.3002);
  BoxManifold m;
  ASSERT_TRUE(recycle(a, b2, m));
  const BoxManifold fresh = collide_boxes(a, c, b2, c, 0.02);
  expect_same_points(m, fresh, 5e-4, 1e-13);
  for (int i = 0; i < m.count; ++i) EXPECT_NEAR(m.points[i].separation, -0.0104, 1e-13);
}

TEST_F(ManifoldRecordTest, AMoveBeyondTheDistanceIsNotRecycled) {
  BoxManifold m;
  m.count = -1;  // untouched when refused
  // 1.5 mm along the face.
  EXPECT_FALSE(recycle(a, on_top(a, {0.2015, 0.99, 0.1}, 0.3), m));
  // A turn about the normal moving b's corners by ~2 mm.
  EXPECT_FALSE(recycle(a, on_top(a, {0.2, 0.99, 0.1}, 0.3 + 2e-3 / c.bounding_radius), m));
  // b tipped 1.5 mrad about a horizontal axis.
  EXPECT_FALSE(recycle(a, pose(b.x, b.R * axis_rotation(0, 1.5e-3)), m));
  EXPECT_EQ(m.count, -1);
}

}  // namespace
}  // namespace tumble
