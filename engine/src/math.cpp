#include "tumble/math.hpp"

#include <cmath>

namespace tumble {

Mat3 skew(const Vec3& a) {
  Mat3 m;
  m << 0.0, -a.z(), a.y(),
       a.z(), 0.0, -a.x(),
       -a.y(), a.x(), 0.0;
  return m;
}

// Rodrigues' formula R = I + a K + b K² with K = skew(v), expanded so that no 3×3 product is
// formed (K² = v vᵀ − |v|² I). Below 1e-4 rad the Taylor series of sin θ/θ and (1 − cos θ)/θ²
// to θ⁴ keeps full precision where the closed form would cancel.
Mat3 rotation_from_vector(const Vec3& v) {
  const double theta2 = v.squaredNorm();
  double a, b;
  if (theta2 < 1e-8) {
    a = 1.0 - theta2 / 6.0 * (1.0 - theta2 / 20.0);
    b = 0.5 - theta2 / 24.0 * (1.0 - theta2 / 30.0);
  } else {
    const double theta = std::sqrt(theta2);
    a = std::sin(theta) / theta;
    b = (1.0 - std::cos(theta)) / theta2;
  }
  const double d = 1.0 - b * theta2;
  const Vec3 av = a * v;
  Mat3 r;
  r << d + b * v.x() * v.x(), b * v.x() * v.y() - av.z(), b * v.x() * v.z() + av.y(),
       b * v.x() * v.y() + av.z(), d + b * v.y() * v.y(), b * v.y() * v.z() - av.x(),
       b * v.x() * v.z() - av.y(), b * v.y() * v.z() + av.x(), d + b * v.z() * v.z();
  return r;
}

Mat3 axis_rotation(int axis, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  Mat3 r = Mat3::Identity();
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  r(i, i) = c;
  r(i, j) = -s;
  r(j, i) = s;
  r(j, j) = c;
  return r;
}

// One Newton step of the polar decomposition, R ← ½ (R + R⁻ᵀ) written with the first-order
// inverse R⁻ᵀ ≈ R (3I − RᵀR)/2, i.e. R ← R (3I − RᵀR)/2 (Björck & Bowie 1971). It converges
// quadratically for R near SO(3), so one step per integration step keeps ‖RᵀR − I‖ at
// round-off; the column Gram–Schmidt that follows removes what is left.
void orthonormalize(Mat3& R) {
  const Mat3 rtr = R.transpose() * R;
  R = R * (1.5 * Mat3::Identity() - 0.5 * rtr);
  Vec3 c0 = R.col(0).normalized();
  Vec3 c1 = (R.col(1) - c0.dot(R.col(1)) * c0).normalized();
  R.col(0) = c0;
  R.col(1) = c1;
  R.col(2) = c0.cross(c1);
}

void gram_schmidt(Mat3& R) {
  const Vec3 c0 = R.col(0).normalized();
  const Vec3 c1 = (R.col(1) - c0.dot(R.col(1)) * c0).normalized();
  R.col(0) = c0;
  R.col(1) = c1;
  R.col(2) = c0.cross(c1);
}

double orthonormality_error(const Mat3& R) {
  return (R.transpose() * R - Mat3::Identity()).norm();
}

double rotation_angle_between(const Mat3& A, const Mat3& B) {
  const Mat3 d = A.transpose() * B;
  // atan2 of (|axis part|, cos part) is accurate at small and large angles alike.
  const Vec3 axis(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
  const double s = 0.5 * axis.norm();
  const double c = 0.5 * (d.trace() - 1.0);
  return std::atan2(s, c);
}

}  // namespace tumble
