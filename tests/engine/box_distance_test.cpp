// box_nearest (box_distance.cpp): the exact distance of two disjoint boxes, checked against
// every corner and every pair of edges, and the speculative contact it gives two boxes whose
// nearest features lie beside each other's faces.
#include <algorithm>
#include <cmath>
#include <random>

#include "box_box.hpp"
#include "box_distance.hpp"
#include "world_fixture.hpp"

namespace tumble {
namespace {

using testing::pose;

BodyConstants box(const Vec3& half) {
  BodyConstants c;
  c.half_extents = half;
  return c;
}

Vec3 corner(const BodyState& s, const Vec3& h, int k) {
  return s.x + s.R * Vec3((k & 1) ? h.x() : -h.x(), (k & 2) ? h.y() : -h.y(),
                          (k & 4) ? h.z() : -h.z());
}

/// Distance of segments p0p1 and q0q1, their parameters clamped to both (Ericson, Real-Time
/// Collision Detection, §5.1.9, for non-degenerate segments).
double segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  const double c = d1.dot(r), b = d1.dot(d2), denom = a * e - b * b;
  double s = denom > 1e-15 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  double t = (b * s + f) / e;
  if (t < 0.0) t = 0.0, s = std::clamp(-c / a, 0.0, 1.0);
  else if (t > 1.0) t = 1.0, s = std::clamp((b - c) / a, 0.0, 1.0);
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

/// Distance of a point to a box (the point clamped into the box's extents).
double point_distance(const Vec3& p, const BodyState& s, const Vec3& h) {
  const Vec3 local = s.R.transpose() * (p - s.x);
  return (local - local.cwiseMax(-h).cwiseMin(h)).norm();
}

/// The boxes' distance by brute force: every corner against the other box, every edge of one
/// against every edge of the other (any nearest pair has a corner or two edge points).
double brute_distance(const BodyState& a, const Vec3& ha, const BodyState& b, const Vec3& hb) {
  double d = INFINITY;
  for (int k = 0; k < 8; ++k) {
    d = std::min(d, point_distance(corner(a, ha, k), b, hb));
    d = std::min(d, point_distance(corner(b, hb, k), a, ha));
  }
  // The 12 edges: corners k and k with one bit flipped.
  for (int ka = 0; ka < 8; ++ka)
    for (int ba = 0; ba < 3; ++ba) {
      if (ka & (1 << ba)) continue;
      for (int kb = 0; kb < 8; ++kb)
        for (int bb = 0; bb < 3; ++bb) {
          if (kb & (1 << bb)) continue;
          d = std::min(d, segment_distance(corner(a, ha, ka), corner(a, ha, ka | (1 << ba)),
                                           corner(b, hb, kb), corner(b, hb, kb | (1 << bb))));
        }
    }
  return d;
}

/// A rotation drawn from a uniform quaternion direction.
Mat3 random_rotation(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  return Quat(Eigen::Vector4d{unit(rng), unit(rng), unit(rng), unit(rng)}.normalized())
      .toRotationMatrix();
}

bool inside(const Vec3& p, const BodyState& s, const Vec3& h) {
  const Vec3 local = s.R.transpose() * (p - s.x);
  return (local.cwiseAbs() - h).maxCoeff() <= 1e-12;
}

TEST(BoxDistance, IsTheLeastDistanceBetweenTheBoxes) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), half(0.1, 0.6), apart(0.3, 1.3);
  int tested = 0;
  for (int k = 0; k < 3000; ++k) {
    const Vec3 ha{half(rng), half(rng), half(rng)}, hb{half(rng), half(rng), half(rng)};
    const Vec3 at{unit(rng), unit(rng), unit(rng)};
    const BodyState a = pose(at, random_rotation(rng));
    const Vec3 dir = Vec3{unit(rng), unit(rng), unit(rng)}.normalized();
    const double gap = apart(rng);
    const BodyState b = pose(a.x + gap * (ha.norm() + hb.norm()) * dir, random_rotation(rng));
    if (box_depth(a, box(ha), b, box(hb), -INFINITY) >= 0.0) continue;  // they overlap
    ++tested;
    const BoxNearest near = box_nearest(a, box(ha), b, box(hb));
    ASSERT_NEAR(near.distance, brute_distance(a, ha, b, hb), 1e-12) << k;
    ASSERT_NEAR((near.on_b - near.on_a).norm(), near.distance, 1e-12) << k;
    ASSERT_TRUE(inside(near.on_a, a, ha) && inside(near.on_b, b, hb)) << k;
    // Every separating axis is a lower bound on the distance.
    ASSERT_GE(near.distance, -box_depth(a, box(ha), b, box(hb), -INFINITY) - 1e-12) << k;
  }
  EXPECT_GT(tested, 1000);
}

// collide_boxes skips the faces' clipping where the reference face shows the boxes farther
// apart than the caller wants (`wanted`, narrow_phase.cpp's touch_limit): exact only while no
// point of the full manifold is nearer than that face's separation, which the nearest points'
// contact (the boxes' distance) keeps too. Pairs a few centimetres apart, corners and edges
// beside each other's faces among them.
TEST(BoxDistance, NoManifoldPointIsNearerThanTheSkipAssumes) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), half(0.1, 0.6), wanted(0.0, 0.05);
  int skipped = 0;
  for (int k = 0; k < 20000; ++k) {
    const BodyConstants ca = box(Vec3{half(rng), half(rng), half(rng)});
    const BodyConstants cb = box(Vec3{half(rng), half(rng), half(rng)});
    const BodyState a = pose(Vec3::Zero(), random_rotation(rng));
    const Vec3 dir = Vec3{unit(rng), unit(rng), unit(rng)}.normalized();
    BodyState b = pose(Vec3::Zero(), random_rotation(rng));
    // Slide b out along dir until the boxes are apart, then a random gap up to 5 cm further.
    double lo = 0.0, hi = 2.0 * (ca.half_extents.norm() + cb.half_extents.norm());
    for (int i = 0; i < 50; ++i) {
      b.x = 0.5 * (lo + hi) * dir;
      (box_depth(a, ca, b, cb, -INFINITY) > 0.0 ? lo : hi) = 0.5 * (lo + hi);
    }
    b.x = (hi + 0.05 * (0.5 + 0.5 * unit(rng))) * dir;
    const double limit = wanted(rng);
    const BoxManifold full = collide_boxes(a, ca, b, cb, 0.1);
    if (full.count == 0 || collide_boxes(a, ca, b, cb, 0.1, limit).count > 0) continue;
    ++skipped;
    for (int i = 0; i < full.count; ++i)
      ASSERT_GT(full.points[i].separation, limit - 1e-12) << k << " point " << i;
  }
  EXPECT_GT(skipped, 1000);
}

// Two boxes of `pile` at step ~400, each beside the other's faces: no face clipping keeps a
// point, so the narrow phase takes the line between their nearest points. Alternating
// projections between the boxes (16 rounds) put that contact 11.5 mm apart, where a face axis
// alone shows 44.8 mm: the solver would have stopped them 3.3 cm before they touched.
TEST(BoxDistance, TheNearestPointsContactIsTheBoxesDistance) {
  Mat3 Ra, Rb;
  Ra << 0.73420898880242835, -0.61022527599737664, -0.29759414190410477, -0.3826576003066996,
      -0.0098685098251676921, -0.92383752545636932, 0.56081219823505379, 0.79216647558941555,
      -0.24075288837937339;
  Rb << 0.91008565083226889, 0.19196187551537691, -0.36728020161427472, -0.24730268158571028,
      0.96271731766815827, -0.10962093751807231, 0.33254396976899248, 0.19059382101852959,
      0.92362790319469756;
  const BodyState a = pose(Vec3(0.95117107503533427, 3.1673317609637857, -2.1727720559181125), Ra);
  const BodyState b = pose(Vec3(0.53574548564869884, 2.8538774203608424, -2.7999143176788328), Rb);
  const Vec3 ha(0.2, 0.2825, 0.2775), hb(0.278, 0.206, 0.2945);
  const BoxManifold m = collide_boxes(a, box(ha), b, box(hb), 0.22114590943289197);
  ASSERT_EQ(m.count, 1);
  EXPECT_EQ(m.points[0].id, 1u << 30);  // the nearest points' contact
  const double distance = brute_distance(a, ha, b, hb);
  EXPECT_NEAR(m.points[0].separation, distance, 1e-12);
  EXPECT_GT(distance, 0.0447);
  EXPECT_NEAR(m.normal.norm(), 1.0, 1e-12);
}

}  // namespace
}  // namespace tumble
