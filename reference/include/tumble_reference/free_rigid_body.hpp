#pragma once
/// Reference solutions of the torque-free rigid body, for tests and benchmarks.
///
/// Two independent integrations of the same motion, so that a test can measure how well the
/// reference itself is known by comparing them:
///   - Method::kQuaternionRkf78: unit quaternion + body angular momentum (Euler's equations),
///     Runge–Kutta–Fehlberg 7(8) with step control, double precision, abs = rel = 1e-13.
///   - Method::kMatrixBulirschStoer: the rotation matrix itself with the world angular
///     momentum held fixed (ω_body = I⁻¹ Rᵀ L), Bulirsch–Stoer extrapolation in long double
///     (x86: 64-bit mantissa) at abs = rel = 1e-17.
/// Usage:
///   auto Rs = tumble_reference::free_rigid_body_attitudes(inertia, R0, L, {1.0, 20.0});
/// Pure functions of their arguments; thread-safe. Header-only (Boost.Numeric.Odeint, Eigen).
#include <array>
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <boost/numeric/odeint.hpp>

namespace tumble_reference {

/// Which integration to run; see the file comment.
enum class Method { kQuaternionRkf78, kMatrixBulirschStoer };

namespace detail {

// State: quaternion (w, x, y, z), then body angular momentum m (kg·m²/s).
using QuatState = std::array<double, 7>;

struct QuaternionEuler {
  std::array<double, 3> inertia;
  void operator()(const QuatState& s, QuatState& ds, double /*t*/) const {
    const double w = s[0], x = s[1], y = s[2], z = s[3];
    const double o0 = s[4] / inertia[0], o1 = s[5] / inertia[1], o2 = s[6] / inertia[2];
    // q̇ = ½ q ⊗ (0, ω_body).
    ds[0] = -0.5 * (x * o0 + y * o1 + z * o2);
    ds[1] = 0.5 * (w * o0 + y * o2 - z * o1);
    ds[2] = 0.5 * (w * o1 + z * o0 - x * o2);
    ds[3] = 0.5 * (w * o2 + x * o1 - y * o0);
    // Euler: ṁ = m × ω.
    ds[4] = s[5] * o2 - s[6] * o1;
    ds[5] = s[6] * o0 - s[4] * o2;
    ds[6] = s[4] * o1 - s[5] * o0;
  }
};

// State: R (body → world) row-major.
using MatState = std::array<long double, 9>;

struct MatrixFixedL {
  std::array<long double, 3> inertia;
  std::array<long double, 3> L;
  void operator()(const MatState& R, MatState& dR, long double /*t*/) const {
    // ω_body = I⁻¹ Rᵀ L; Ṙ = R ω̂.
    long double w[3];
    for (int j = 0; j < 3; ++j) {
      w[j] = (R[0 * 3 + j] * L[0] + R[1 * 3 + j] * L[1] + R[2 * 3 + j] * L[2]) / inertia[j];
    }
    for (int i = 0; i < 3; ++i) {
      const long double r0 = R[i * 3 + 0], r1 = R[i * 3 + 1], r2 = R[i * 3 + 2];
      dR[i * 3 + 0] = r1 * w[2] - r2 * w[1];
      dR[i * 3 + 1] = r2 * w[0] - r0 * w[2];
      dR[i * 3 + 2] = r0 * w[1] - r1 * w[0];
    }
  }
};

}  // namespace detail

/// Attitude R(t) (body → world) of a torque-free rigid body at each of `times` (seconds,
/// ascending, ≥ 0), starting from orientation R0 at t = 0 with principal moments `inertia`
/// (kg·m², body axes) and constant world angular momentum L (kg·m²/s). `tolerance` ≤ 0 means
/// the method's default (1e-13 for kQuaternionRkf78, 1e-17 for kMatrixBulirschStoer).
inline std::vector<Eigen::Matrix3d> free_rigid_body_attitudes(
    const Eigen::Vector3d& inertia, const Eigen::Matrix3d& R0, const Eigen::Vector3d& L,
    const std::vector<double>& times, Method method = Method::kQuaternionRkf78,
    double tolerance = 0.0) {
  namespace odeint = boost::numeric::odeint;
  std::vector<Eigen::Matrix3d> out;
  out.reserve(times.size());
  if (times.empty()) return out;
  // odeint's integrate_times wants the start time first; it observes it too.
  std::vector<double> grid;
  grid.reserve(times.size() + 1);
  grid.push_back(0.0);
  grid.insert(grid.end(), times.begin(), times.end());

  if (method == Method::kQuaternionRkf78) {
    const double tol = tolerance > 0.0 ? tolerance : 1e-13;
    const Eigen::Quaterniond q0(R0);
    const Eigen::Vector3d m0 = R0.transpose() * L;
    detail::QuatState s{q0.w(), q0.x(), q0.y(), q0.z(), m0[0], m0[1], m0[2]};
    const detail::QuaternionEuler sys{{inertia[0], inertia[1], inertia[2]}};
    auto stepper = odeint::make_controlled(tol, tol,
                                           odeint::runge_kutta_fehlberg78<detail::QuatState>());
    bool first = true;
    odeint::integrate_times(stepper, sys, s, grid.begin(), grid.end(), 1e-3,
                            [&](const detail::QuatState& x, double) {
                              if (first) { first = false; return; }
                              Eigen::Quaterniond q(x[0], x[1], x[2], x[3]);
                              out.push_back(q.normalized().toRotationMatrix());
                            });
    return out;
  }

  using Ld = long double;
  const Ld tol = tolerance > 0.0 ? Ld(tolerance) : Ld(1e-17L);
  detail::MatState s{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s[i * 3 + j] = R0(i, j);
  const detail::MatrixFixedL sys{{inertia[0], inertia[1], inertia[2]}, {L[0], L[1], L[2]}};
  odeint::bulirsch_stoer<detail::MatState, Ld> stepper(tol, tol);
  std::vector<Ld> grid_ld(grid.begin(), grid.end());
  bool first = true;
  odeint::integrate_times(stepper, sys, s, grid_ld.begin(), grid_ld.end(), Ld(1e-3),
                          [&](const detail::MatState& x, Ld) {
                            if (first) { first = false; return; }
                            using M3 = Eigen::Matrix<Ld, 3, 3>;
                            M3 r;
                            for (int i = 0; i < 3; ++i)
                              for (int j = 0; j < 3; ++j) r(i, j) = x[i * 3 + j];
                            // One polar (Björck–Bowie) step removes the drift from SO(3).
                            const M3 rtr = r.transpose() * r;
                            r = r * (Ld(1.5) * M3::Identity() - Ld(0.5) * rtr);
                            out.push_back(r.template cast<double>());
                          });
  return out;
}

/// Convenience: R(t) at a single time t (seconds, ≥ 0); see free_rigid_body_attitudes.
inline Eigen::Matrix3d free_rigid_body_attitude(const Eigen::Vector3d& inertia,
                                               const Eigen::Matrix3d& R0,
                                               const Eigen::Vector3d& L, double t,
                                               Method method = Method::kQuaternionRkf78,
                                               double tolerance = 0.0) {
  return free_rigid_body_attitudes(inertia, R0, L, {t}, method, tolerance).front();
}

}  // namespace tumble_reference
