#pragma once
/// Torque-free rotation of a rigid body: exact flows and the splitting approximation.
/// Pure functions; thread-safe.
#include <array>

#include "tumble/math.hpp"

namespace tumble {

/// What the exact step of a general box (three distinct moments) computes from its constants
/// of motion alone, kept for the body's next step. Over torque-free flight L and the kinetic
/// energy are constant, and with them the polhode's amplitudes, rate, modulus and
/// characteristic; with the step t constant too, so are the elliptic functions and the R_J of
/// the increment λt: half the step's work. The memo applies to a step that starts exactly where
/// the memoised step ended (R, L and t equal bit for bit), so any impulse, contact, Gram–Schmidt
/// pass or edit of the state sets it aside. Its values come from an earlier state of the same
/// flight, so they differ from values computed afresh by round-off: a World keeps the memos
/// with its state and copies them (results depend on them). One per body; not thread-safe.
struct PolhodeMemo {
  Mat3 R_end = Mat3::Zero();          ///< Attitude the memoised step ended at (key).
  Vec3 L = Vec3::Zero();              ///< Its world angular momentum, kg·m²/s (key).
  double t = 0.0;                     ///< Its step, s (key).
  std::array<int, 3> axes{};          ///< Canonical axes (body axes in order J1, J2, J3).
  bool held = false;                  ///< Whether the fields below are set.
  double a1 = 0.0, a2 = 0.0, a3 = 0.0;  ///< Amplitudes of m1, m2, m3, kg·m²/s.
  double lambda = 0.0;                ///< Rate of the elliptic argument, 1/s.
  double k2 = 0.0, kc2 = 0.0;         ///< k², k'² = 1 − k².
  double n = 0.0;                     ///< Characteristic of Π (< 0).
  double s = 1.0;                     ///< sign(J3 − J2).
  double M = 0.0;                     ///< |L|, kg·m²/s.
  double c = 0.0;                     ///< Coefficient of the Π bracket in ψ.
  double w = 0.0;                     ///< √(−n (k² − n)(1 − n)).
  double sn = 0.0, cn = 1.0, dn = 1.0;  ///< Jacobi functions at the increment λt.
  double head = 0.0;                  ///< sn³ R_J(cn², dn², 1, 1 − n sn²) at λt.
};

/// Exact torque-free attitude after t seconds: R(t) for a body with principal moments
/// `inertia` (kg·m², body axes), starting at orientation R (body → world) with constant world
/// angular momentum L (kg·m²/s). Cube: one rotation; two equal moments: regular precession;
/// general: Jacobi elliptic functions and elliptic integrals (Celledoni, Fassò, Säfström &
/// Zanna, SIAM J. Sci. Comput. 30(4), 2008).
Mat3 free_rotation_exact(const Vec3& inertia, const Mat3& R, const Vec3& L, double t);

/// free_rotation_exact with a general box's constants taken from `memo` when it holds those of
/// the step that ended at (R, L) with this t, and kept there for the next step (memo may be
/// null: then the same as above). Equal to the above to round-off.
Mat3 free_rotation_exact(const Vec3& inertia, const Mat3& R, const Vec3& L, double t,
                         PolhodeMemo* memo);

/// Second-order symmetric splitting of the free rotation (McLachlan 1993; Dullweber,
/// Leimkuhler & McLachlan 1997): H = T1 + T2 + T3, each an exact rotation about one body axis.
/// L is conserved exactly, R stays orthonormal to round-off.
Mat3 free_rotation_splitting(const Vec3& inertia, const Mat3& R, const Vec3& L, double t);

}  // namespace tumble
