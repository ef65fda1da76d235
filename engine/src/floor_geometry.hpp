#pragma once
/// A box against the floor plane y = h: its vertices' heights, the vertices that touch, its
/// velocities through an impulse exchange. Shared by the floor's resting contact
/// (floor_contact.cpp), impulses (floor_impulse.cpp) and time of impact
/// (floor_time_of_impact.cpp); inline, pure, thread-safe.
#include <algorithm>
#include <array>
#include <cmath>

#include "active_set.hpp"
#include "tumble/body.hpp"

namespace tumble {

/// Height of the lowest vertex above the plane y = 0 (metres): x_y − Σ |R_1k| h_k.
inline double lowest_vertex_y(const BodyState& s, const BodyConstants& c) {
  return s.x.y() - (s.R.row(1).cwiseAbs().dot(c.half_extents));
}

}  // namespace tumble

namespace tumble::floor_detail {

constexpr double kSlop = 1e-12;          // m: deeper than this below the floor is penetration.
constexpr double kSimultaneous = 1e-9;   // m: vertices this close to the lowest hit together.
constexpr double kContactBand = 1e-6;    // m: vertices this close to the floor are touching.
constexpr int kMaxPoints = kMaxActiveSetPoints;  // a box has 8 vertices

/// Body-frame offsets and world velocities of the vertices touching the floor.
struct ContactSet {
  int count = 0;
  std::array<Vec3, kMaxPoints> r;  // world offset from the centre of mass, m
};

/// The box's half edges in the world: R's columns times the half extents. Vertex i is the
/// centre plus ±a ± b ± c (the signs of body_vertex): three products for all eight vertices
/// instead of eight 3×3 products, to the same bits (R (±h) sums the same three products).
struct HalfEdges {
  Vec3 a, b, c;
  HalfEdges(const BodyState& s, const BodyConstants& k)
      : a(s.R.col(0) * k.half_extents.x()),
        b(s.R.col(1) * k.half_extents.y()),
        c(s.R.col(2) * k.half_extents.z()) {}
  /// Offset of vertex i from the centre of mass, world, m.
  Vec3 vertex(int i) const {
    return ((i & 1) ? a : Vec3(-a)) + ((i & 2) ? b : Vec3(-b)) + ((i & 4) ? c : Vec3(-c));
  }
  /// Its height alone.
  double vertex_y(int i) const {
    return ((i & 1) ? a.y() : -a.y()) + ((i & 2) ? b.y() : -b.y()) + ((i & 4) ? c.y() : -c.y());
  }
};

/// Height of the lowest of the vertices in `mask` (bit i: vertex i), m; +∞ for an empty mask.
inline double lowest_masked_y(const BodyState& s, const BodyConstants& c, unsigned mask) {
  const HalfEdges e(s, c);
  double lowest = INFINITY;
  for (int i = 0; i < 8; ++i)
    if (mask & (1u << i)) lowest = std::min(lowest, s.x.y() + e.vertex_y(i));
  return lowest;
}

/// The body's bounding sphere lies wholly above the floor plane y = floor_y.
inline bool clear_of_floor(const BodyState& s, const BodyConstants& c, double floor_y) {
  return s.x.y() - c.bounding_radius > floor_y;
}

/// The vertices at or below the height limit_y (m), as offsets from the centre.
inline ContactSet touching_vertices(const BodyState& s, const BodyConstants& c, double limit_y) {
  ContactSet set;
  const HalfEdges e(s, c);
  for (int i = 0; i < 8; ++i)
    if (s.x.y() + e.vertex_y(i) <= limit_y) set.r[set.count++] = e.vertex(i);
  return set;
}

/// Kinematic state of the body during an impulse exchange (I⁻¹ is fixed over an impulse).
struct Kinematics {
  Vec3 v;
  Vec3 w;
  Mat3 inv_inertia;
  double inv_mass;
  Vec3 point_velocity(const Vec3& r) const { return v + w.cross(r); }
  void apply(BodyState& s, const Vec3& r, const Vec3& j) {
    s.P += j;
    s.L += r.cross(j);
    v += inv_mass * j;
    w += inv_inertia * r.cross(j);
  }
};

/// The body's kinematics now (v = P / m, ω = I⁻¹ L, I⁻¹ in the world).
inline Kinematics kinematics_of(const BodyState& s, const BodyConstants& c) {
  Kinematics k;
  k.inv_mass = c.inv_mass;
  k.inv_inertia = inverse_inertia_world(s, c);
  k.v = s.P * c.inv_mass;
  k.w = k.inv_inertia * s.L;
  return k;
}

/// Vertical speed of vertex i (offset r from the centre, world) of a body moving at v, ω:
/// (v + ω × r)_y, m/s.
inline double vertex_speed_y(const Vec3& v, const Vec3& w, const Vec3& r) {
  return v.y() + w.z() * r.x() - w.x() * r.z();
}

/// Bit i set when vertex i lies above the height y (m).
inline unsigned vertices_above(const BodyState& s, const BodyConstants& c, double y) {
  const HalfEdges e(s, c);
  unsigned mask = 0;
  for (int i = 0; i < 8; ++i)
    if (s.x.y() + e.vertex_y(i) > y) mask |= 1u << i;
  return mask;
}

}  // namespace tumble::floor_detail
