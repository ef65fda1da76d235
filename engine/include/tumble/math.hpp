#pragma once
/// Small geometric helpers over Eigen's fixed-size types. Pure functions; thread-safe.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace tumble {

using Vec3 = Eigen::Vector3d;     ///< A 3-vector (metres, m/s, N·s … as named).
using Mat3 = Eigen::Matrix3d;     ///< A 3×3 matrix; rotations map body frame to world.
using Quat = Eigen::Quaterniond;  ///< A unit quaternion [w, x, y, z].

/// The seed's a* operator: skew(a) * b == a × b.
Mat3 skew(const Vec3& a);

/// exp of skew(rotation_vector): a rotation by |v| radians about v (Rodrigues' formula).
Mat3 rotation_from_vector(const Vec3& rotation_vector);

/// sin θ / θ and (1 − cos θ) / θ² from θ² (rad²), accurate at every angle, with no library
/// call below θ = 0.5 rad.
void sinc_and_versine(double theta2, double& sinc, double& versine);

/// sin x and cos x, with no library call below 0.5 rad (a step's small turns).
void small_angle_sin_cos(double x, double& s, double& c);

/// Rotation by `angle` radians about the principal body axis `axis` (0, 1 or 2).
Mat3 axis_rotation(int axis, double angle);

/// Re-orthonormalises R in place (symmetric polar step, then a Gram–Schmidt finish).
void orthonormalize(Mat3& R);

/// Column Gram–Schmidt in place: enough for an R that is a product of exact rotations and
/// only gathers round-off (about a third of orthonormalize's cost).
void gram_schmidt(Mat3& R);

/// ‖RᵀR − I‖ (Frobenius): how far R is from a rotation.
double orthonormality_error(const Mat3& R);

/// Geodesic angle between two rotations, ‖log(AᵀB)‖ in radians.
double rotation_angle_between(const Mat3& A, const Mat3& B);

/// True when every coefficient is finite.
template <typename Derived>
bool all_finite(const Eigen::MatrixBase<Derived>& m) {
  return ((m.derived().array() - m.derived().array()) == 0).all();
}

}  // namespace tumble
