#pragma once
/// The distance between two disjoint boxes and a pair of nearest points, exact to round-off.
/// Pure functions; thread-safe.
#include <cstdint>

#include "tumble/body.hpp"

namespace tumble {

/// The nearest points of two boxes and their distance.
struct BoxNearest {
  Vec3 on_a = Vec3::Zero();  ///< Point of box a, world, m.
  Vec3 on_b = Vec3::Zero();  ///< Point of box b, world, m.
  double distance = 0.0;     ///< |on_b − on_a|, m.
};

/// The nearest points of an edge of each of two boxes.
struct EdgeNearest {
  Vec3 on_a = Vec3::Zero();  ///< Point of box a's edge, world, m.
  Vec3 on_b = Vec3::Zero();  ///< Point of box b's edge, world, m.
  std::uint32_t corners = 0;  ///< Which edges: bit k (3 + k) set where a's (b's) edge lies on
                              ///< the + side of its axis k.
};

/// The nearest points of the lines of box a's edge along axis i that reaches farthest along n
/// and box b's edge along axis j that reaches farthest along −n (n ⟂ both, from a towards b,
/// any length), in `out`; false, `out` unset, when the edges are within 1e-6 rad of parallel or
/// those points fall outside either edge (a corner is then as near).
bool extreme_edges_nearest(const BodyState& a, const Vec3& ha, int i, const BodyState& b,
                           const Vec3& hb, int j, const Vec3& n, EdgeNearest& out);

/// The nearest points of boxes a and b, which must be disjoint (some separating axis shows a
/// gap): a corner of either box and the other box's nearest point, or two edges' nearest
/// points, whichever pair is closest.
BoxNearest box_nearest(const BodyState& a, const BodyConstants& ca, const BodyState& b,
                       const BodyConstants& cb);

}  // namespace tumble
