#include "pivot_turns.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

#include "free_rotation.hpp"

namespace tumble {
namespace {

/// The principal axes (columns, body frame, a proper rotation) and moments (kg·m²) of the
/// inertia about a point `arm` (body frame, m) from the centre: I + m (|d|² 1 − d dᵀ). A cube's
/// (equal moments) are d itself and any two axes square to it, found without an eigensolver.
void principal_axes_about(const BodyConstants& c, const Vec3& arm, Mat3& axes, Vec3& moments) {
  const double d2 = arm.squaredNorm();
  if (c.inertia.x() == c.inertia.y() && c.inertia.y() == c.inertia.z() && d2 > 0.0) {
    const Vec3 along = arm / std::sqrt(d2);
    const Vec3 across = along.unitOrthogonal();
    axes.col(0) = along;
    axes.col(1) = across;
    axes.col(2) = along.cross(across);
    moments = Vec3(c.inertia.x(), c.inertia.x() + c.mass * d2, c.inertia.x() + c.mass * d2);
    return;
  }
  Mat3 inertia = c.mass * (d2 * Mat3::Identity() - arm * arm.transpose());
  inertia.diagonal() += c.inertia;
  Eigen::SelfAdjointEigenSolver<Mat3> principal;
  principal.computeDirect(inertia);
  axes = principal.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
  moments = principal.eigenvalues();
}

}  // namespace

// A box on an edge whose two vertices stick is a pendulum about that edge, and moving it with
// its end-of-step velocities (symplectic Euler, floor_contact.cpp's resting step) tipped it
// over about half a step early at any angle. Moving it with the mean of its start and end angular velocities
// alone would not help: with the end velocity from the start's torque that scheme is late by
// 0.3–1.5 steps (checked on θ̈ = λ² sin θ). Störmer–Verlet is second order (Hairer, Lubich &
// Wanner, Geometric Numerical Integration, §I.1.4): θ₁ = θ₀ + h ω̄ with ω̄ = ω₀ + (h/2) α(θ₀),
// then ω₁ = ω̄ + (h/2) α(θ₁). The contact solve has already found ω₀ + h α(θ₀) (its impulses
// hold both vertices still, so it is the exact change about the edge), hence ω̄ is the mean
// of the start and end rates; the turn through h ω̄ about the edge is exact, and α(θ₁) =
// a · ((x₁ − p) × m g) / I_a, the pivot's vertices giving no torque about their own edge and
// I_a = aᵀ I a + m |a × (x − p)|² not changing as the body turns about a. The momenta are
// those of the turn. r0, r1: the edge's vertices from the centre (world, m); w_start, w_end:
// the angular velocities before and after the solve (rad/s).
void edge_step(BodyState& s, const BodyConstants& c, const Vec3& gravity, double h,
               const Vec3& w_start, const Vec3& w_end, const Vec3& r0, const Vec3& r1) {
  const Vec3 axis = (r1 - r0).normalized();
  const double w_mid = 0.5 * (axis.dot(w_start) + axis.dot(w_end));
  const Mat3 turn = rotation_from_vector((h * w_mid) * axis);
  const Vec3 pivot = s.x + r0;
  const Vec3 arm = turn * (-r0);  // from the pivot to the centre, at the end
  s.x = pivot + arm;
  s.R = turn * s.R;
  orthonormalize(s.R);
  const Vec3 body_axis = s.R.transpose() * axis;
  const double inertia = body_axis.dot(c.inertia.cwiseProduct(body_axis)) +
                         c.mass * axis.cross(arm).squaredNorm();
  const double w_new = w_mid + 0.5 * h * axis.dot(arm.cross(c.mass * gravity)) / inertia;
  const Vec3 w = w_new * axis;
  s.P = c.mass * w.cross(arm);
  s.L = s.R * c.inertia.cwiseProduct(s.R.transpose() * w);
}

// A box on one corner that sticks is a heavy top about that corner, and the first-order
// resting step tipped it over about half a step early too. The heavy top's splitting (Touma &
// Wisdom, Astron. J. 107, 1994; McLachlan & Zanna, Found. Comput. Math. 5, 2005) is second
// order: about the pivot p the angular momentum L_p = L + (x − p) × P changes only by gravity's
// torque (the floor's impulses act at p), so half a step's torque, then the free rotation
// about p with L_p fixed, exactly (free_rotation_exact, in the principal axes of the inertia
// about p, I_p = I + m (|d|² 1 − d dᵀ) with d the centre from the corner, fixed in the body),
// then the other half at the end. The momenta are then those of the turn about p. The
// contact solve before it only decides that the corner sticks.
// p_start, L_start: the momenta before the solve; r0: the corner from the centre (world, m).
void corner_step(BodyState& s, const BodyConstants& c, const Vec3& gravity, double h,
                 const Vec3& p_start, const Vec3& L_start, const Vec3& r0) {
  const Vec3 pivot = s.x + r0;
  const Vec3 weight = c.mass * gravity;
  const Vec3 arm = -r0;  // from the pivot to the centre, world
  const Vec3 arm_body = s.R.transpose() * arm;
  Mat3 axes;
  Vec3 moments;
  principal_axes_about(c, arm_body, axes, moments);
  Vec3 momentum = L_start + arm.cross(p_start) + (0.5 * h) * arm.cross(weight);
  s.R = free_rotation_exact(moments, s.R * axes, momentum, h) * axes.transpose();
  orthonormalize(s.R);
  const Vec3 arm_end = s.R * arm_body;
  s.x = pivot + arm_end;
  momentum += (0.5 * h) * arm_end.cross(weight);
  const Mat3 frame = s.R * axes;  // world ← the pivot's principal axes
  const Vec3 w = frame * (frame.transpose() * momentum).cwiseQuotient(moments);
  s.P = c.mass * w.cross(arm_end);
  s.L = momentum - arm_end.cross(s.P);
}

}  // namespace tumble
