/// Penetration measured the same way for every engine, from the poses it reports.
#include <algorithm>
#include <cmath>
#include <numeric>

#include "contact/contact.hpp"

namespace tumble_bench::contact {
namespace {

struct Box {
  Vec3 x;
  Eigen::Matrix3d R;  // columns: body axes in the world
  Vec3 h;             // half extents
  double radius;
};

/// Penetration depth of two boxes (m, > 0 when they overlap, else ≤ 0): the smallest overlap of
/// their projections over the 15 separating axes, which for two boxes is the exact minimum
/// translation distance.
double box_box_depth(const Box& a, const Box& b) {
  const Vec3 d = b.x - a.x;
  double depth = INFINITY;
  auto test = [&](Vec3 axis) {
    const double len = axis.norm();
    if (len < 1e-9) return;
    axis /= len;
    const double ra = (a.R.transpose() * axis).cwiseAbs().dot(a.h);
    const double rb = (b.R.transpose() * axis).cwiseAbs().dot(b.h);
    depth = std::min(depth, ra + rb - std::abs(d.dot(axis)));
  };
  for (int i = 0; i < 3; ++i) test(a.R.col(i));
  for (int i = 0; i < 3; ++i) test(b.R.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) test(a.R.col(i).cross(b.R.col(j)));
  return depth;
}

/// The boxes as the engine reports them; *floor_depth gets the deepest box–floor overlap.
std::vector<Box> boxes_of(const PeerWorld& w, const tumble::Scene& s, double* floor_depth) {
  std::vector<Box> boxes(s.bodies.size());
  const double floor_y = s.world.floor ? s.world.floor->height : -INFINITY;
  *floor_depth = 0.0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const PeerBodyState st = w.state(i);
    const Vec3 h = s.bodies[i].size * 0.5;
    boxes[i] = {st.position, st.orientation.toRotationMatrix(), h, h.norm()};
    *floor_depth = std::max(*floor_depth,
                            floor_y - (st.position.y() - boxes[i].R.row(1).cwiseAbs().dot(h)));
  }
  return boxes;
}

}  // namespace

double deepest_penetration(const PeerWorld& w, const tumble::Scene& s) {
  double deepest = 0.0;
  const std::vector<Box> boxes = boxes_of(w, s, &deepest);
  const std::size_t n = boxes.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t i, std::size_t j) { return boxes[i].x.x() < boxes[j].x.x(); });
  for (std::size_t a = 0; a < n; ++a) {
    const Box& A = boxes[order[a]];
    for (std::size_t b = a + 1; b < n; ++b) {
      const Box& B = boxes[order[b]];
      if (B.x.x() - A.x.x() > A.radius + B.radius + 1.0) break;  // radii ≤ 0.87 m here
      if ((A.x - B.x).norm() > A.radius + B.radius) continue;
      deepest = std::max(deepest, box_box_depth(A, B));
    }
  }
  return deepest;
}

}  // namespace tumble_bench::contact
