#pragma once
/// A rigid box: immutable definition, mutable state (the seed's x, R, P, L) and derived
/// quantities. Plain data; not synchronised (the World's owner thread alone touches it).
#include <array>
#include <optional>
#include <string>

#include "tumble/math.hpp"

namespace tumble {

/// How a body is described in a scene (SI units; angular velocity in the world frame).
struct BodyDef {
  std::string name = "box";           ///< Unique name within a scene.
  Vec3 size{1.0, 1.0, 1.0};           ///< Full edge lengths along body x, y, z, metres.
  double mass = 1.0;                  ///< kg.
  Vec3 position{0.0, 0.0, 0.0};       ///< Centre of mass, world, metres.
  Quat orientation = Quat::Identity();///< Body → world rotation.
  Vec3 velocity{0.0, 0.0, 0.0};       ///< Linear velocity, m/s.
  Vec3 angular_velocity{0.0, 0.0, 0.0};///< World frame, rad/s.
  std::optional<double> restitution;  ///< Overrides the floor's e when set.
  std::optional<double> friction;     ///< Overrides the floor's μ when set.
  std::string color = "#d9822b";      ///< "#rrggbb", for viewers only.
};

/// The seed's state vector Y = (x, R, P, L), world frame.
struct BodyState {
  Vec3 x = Vec3::Zero();   ///< Centre of mass, m.
  Mat3 R = Mat3::Identity();///< Orientation, body → world.
  Vec3 P = Vec3::Zero();   ///< Linear momentum, kg·m/s.
  Vec3 L = Vec3::Zero();   ///< Angular momentum about the centre of mass, kg·m²/s.
};

/// Which closed form the torque-free rotation of a box has (decided once, from I_body).
enum class InertiaShape : unsigned char {
  isotropic,  ///< Three equal moments (a cube): ω is constant, one rotation per step.
  symmetric,  ///< Two equal moments: regular precession.
  general,    ///< Three distinct moments: Jacobi elliptic functions.
};

/// Constants of a box derived from its definition once (principal axes = body axes).
struct BodyConstants {
  double mass = 1.0;                     ///< kg.
  double inv_mass = 1.0;                 ///< 1/kg.
  Vec3 inertia = Vec3::Ones();           ///< Principal moments I_body (diagonal), kg·m².
  Vec3 inv_inertia = Vec3::Ones();       ///< I_body⁻¹ diagonal.
  Vec3 half_extents{0.5, 0.5, 0.5};      ///< Half edge lengths, m.
  double bounding_radius = 0.866;        ///< |half_extents|, m.
  double restitution = 1.0;              ///< e used against the floor.
  double friction = 0.0;                 ///< μ used against the floor.
  InertiaShape shape = InertiaShape::isotropic;  ///< Closed form of its free rotation.
};

/// Computes the box constants (inertia of a solid cuboid: m/12 (b² + c²) …).
BodyConstants make_body_constants(const BodyDef& def, double floor_restitution,
                                  double floor_friction);

/// The initial state a definition describes (P = m v, L = I ω with I = R I_body Rᵀ).
BodyState make_body_state(const BodyDef& def, const BodyConstants& c);

/// Body-frame vertex i (0…7) of a box: bit 0 → +x, bit 1 → +y, bit 2 → +z.
Vec3 body_vertex(const BodyConstants& c, int i);

/// The 6 faces as vertex-index quads, counter-clockwise seen from outside.
inline constexpr std::array<std::array<int, 4>, 6> kBoxFaces{{
    {0, 4, 6, 2},  // −x
    {1, 3, 7, 5},  // +x
    {0, 1, 5, 4},  // −y
    {2, 6, 7, 3},  // +y
    {0, 2, 3, 1},  // −z
    {4, 5, 7, 6},  // +z
}};

/// Linear velocity v = P / m, m/s.
inline Vec3 velocity(const BodyState& s, const BodyConstants& c) { return s.P * c.inv_mass; }

/// Angular velocity ω = R I_body⁻¹ Rᵀ L, rad/s, world frame.
Vec3 angular_velocity(const BodyState& s, const BodyConstants& c);

/// A bound on the speed of every point of the box: |v| + |ω| r (r its bounding radius), m/s.
double point_speed_bound(const BodyState& s, const BodyConstants& c);

/// World-frame inverse inertia I⁻¹ = R I_body⁻¹ Rᵀ.
Mat3 inverse_inertia_world(const BodyState& s, const BodyConstants& c);

/// World position of vertex i: x + R r_i, metres.
Vec3 world_vertex(const BodyState& s, const BodyConstants& c, int i);

/// Kinetic energy ½ P²/m + ½ L·ω, J.
double kinetic_energy(const BodyState& s, const BodyConstants& c);

/// Kinetic + potential energy (−m g·x, zero at the origin), J.
double total_energy(const BodyState& s, const BodyConstants& c, const Vec3& gravity);

/// Why a body is not moving (or is).
enum class Activity : unsigned char {
  awake,   ///< Integrated every step.
  asleep,  ///< Still and resting: skipped until an impulse or a contact wakes it.
  frozen,  ///< Went non-finite: kept at its last finite state and reported, never stepped.
};

/// One body in a World: constants, state and bookkeeping.
struct Body {
  BodyConstants c;              ///< Immutable after creation.
  BodyState s;                  ///< Mutable state.
  Activity activity = Activity::awake;
  double still_time = 0.0;      ///< Seconds it has been slow and in contact (for sleeping).
  bool in_contact = false;      ///< Touched the floor during the last step.
};

}  // namespace tumble
