#include "tumble/body.hpp"

#include <cmath>

namespace tumble {

BodyConstants make_body_constants(const BodyDef& def, double floor_restitution,
                                  double floor_friction) {
  BodyConstants c;
  c.mass = def.mass;
  c.inv_mass = 1.0 / def.mass;
  const Vec3 s2 = def.size.cwiseProduct(def.size);
  // Solid cuboid about its centre: I_x = m (b² + c²) / 12 and cyclic.
  c.inertia = def.mass / 12.0 * Vec3(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y());
  c.inv_inertia = c.inertia.cwiseInverse();
  c.half_extents = 0.5 * def.size;
  c.bounding_radius = c.half_extents.norm();
  c.restitution = def.restitution.value_or(floor_restitution);
  c.friction = def.friction.value_or(floor_friction);
  const double tol = 1e-14 * c.inertia.maxCoeff();
  const bool xy = std::abs(c.inertia.x() - c.inertia.y()) <= tol;
  const bool yz = std::abs(c.inertia.y() - c.inertia.z()) <= tol;
  const bool xz = std::abs(c.inertia.x() - c.inertia.z()) <= tol;
  c.shape = (xy && yz) ? InertiaShape::isotropic
            : (xy || yz || xz) ? InertiaShape::symmetric
                               : InertiaShape::general;
  return c;
}

BodyState make_body_state(const BodyDef& def, const BodyConstants& c) {
  BodyState s;
  s.x = def.position;
  s.R = def.orientation.normalized().toRotationMatrix();
  s.P = c.mass * def.velocity;
  const Mat3 inertia_world = s.R * c.inertia.asDiagonal() * s.R.transpose();
  s.L = inertia_world * def.angular_velocity;
  return s;
}

Vec3 body_vertex(const BodyConstants& c, int i) {
  return Vec3((i & 1) ? c.half_extents.x() : -c.half_extents.x(),
              (i & 2) ? c.half_extents.y() : -c.half_extents.y(),
              (i & 4) ? c.half_extents.z() : -c.half_extents.z());
}

// A cube's inertia is a multiple of the identity in every frame: ω = L / I and I⁻¹ = 1/I
// without the rotations to and from the body frame (exactly what they give for an
// orthonormal R; they cost a cube's floor contact a tenth of its instructions).
Vec3 angular_velocity(const BodyState& s, const BodyConstants& c) {
  if (c.shape == InertiaShape::isotropic) return c.inv_inertia.x() * s.L;
  const Vec3 m = s.R.transpose() * s.L;
  const Vec3 w_body = c.inv_inertia.cwiseProduct(m);
  return s.R * w_body;
}

Mat3 inverse_inertia_world(const BodyState& s, const BodyConstants& c) {
  if (c.shape == InertiaShape::isotropic) return c.inv_inertia.x() * Mat3::Identity();
  return s.R * c.inv_inertia.asDiagonal() * s.R.transpose();
}

Vec3 world_vertex(const BodyState& s, const BodyConstants& c, int i) {
  return s.x + s.R * body_vertex(c, i);
}

double kinetic_energy(const BodyState& s, const BodyConstants& c) {
  const Vec3 m = s.R.transpose() * s.L;
  return 0.5 * s.P.squaredNorm() * c.inv_mass + 0.5 * m.cwiseProduct(c.inv_inertia).dot(m);
}

double total_energy(const BodyState& s, const BodyConstants& c, const Vec3& gravity) {
  return kinetic_energy(s, c) - c.mass * gravity.dot(s.x);
}

double point_speed_bound(const BodyState& s, const BodyConstants& c) {
  return s.P.norm() * c.inv_mass + angular_velocity(s, c).norm() * c.bounding_radius;
}

}  // namespace tumble
