#include "tumble/math.hpp"

#include <cmath>

#include "rotation_series.hpp"

namespace tumble {

Mat3 skew(const Vec3& a) {
  Mat3 m;
  m << 0.0, -a.z(), a.y(),
       a.z(), 0.0, -a.x(),
       -a.y(), a.x(), 0.0;
  return m;
}

// a = sin θ/θ and b = (1 − cos θ)/θ² are even functions of θ: below θ = 0.5 rad (every step
// of a body spinning under 120 rad/s at dt 1/240) their Taylor series in θ² to θ¹² leaves out
// less than 5e-17, under half an ulp of a ≈ 1 and b ≈ ½, and costs no square root, sine or
// cosine (the library's sincos was half the cost of a cube's step). The closed form is used
// above, where it does not cancel.
void sinc_and_versine(double t, double& a, double& b) {
  if (t < 0.25) {
    sinc_versine_series(t, a, b);
    return;
  }
  const double theta = std::sqrt(t);
  a = std::sin(theta) / theta;
  b = (1.0 - std::cos(theta)) / t;
}

void small_angle_sin_cos(double x, double& s, double& c) {
  double a, b;
  sinc_and_versine(x * x, a, b);
  s = a * x;
  c = 1.0 - b * (x * x);
}

// Rodrigues' formula R = I + a K + b K² with K = skew(v), expanded so that no 3×3 product is
// formed (K² = v vᵀ − |v|² I), a and b from sinc_and_versine.
Mat3 rotation_from_vector(const Vec3& v) {
  const double t = v.squaredNorm();
  double a, b;
  sinc_and_versine(t, a, b);
  const double d = 1.0 - b * t;
  const Vec3 av = a * v;
  const Vec3 bv = b * v;
  Mat3 r;
  r(0, 0) = d + bv.x() * v.x();
  r(1, 1) = d + bv.y() * v.y();
  r(2, 2) = d + bv.z() * v.z();
  r(0, 1) = bv.x() * v.y() - av.z();
  r(1, 0) = bv.x() * v.y() + av.z();
  r(0, 2) = bv.x() * v.z() + av.y();
  r(2, 0) = bv.x() * v.z() - av.y();
  r(1, 2) = bv.y() * v.z() - av.x();
  r(2, 1) = bv.y() * v.z() + av.x();
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
