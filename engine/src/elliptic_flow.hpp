#pragma once
/// The general box's torque-free flow (free_rotation.cpp explains it) cut where one body at a
/// time and four in SIMD lanes (free_rotation_lanes.cpp) meet: the reduction to the elliptic
/// case, the phase along the polhode (Jacobi sn, cn, dn and the angle ψ about L), and the
/// rotation assembled from them. Their formulas are templates over double and Lanes,
/// written once, so that each lane rounds as the scalar does: the same bits either way.
/// Internal to the engine; pure functions, thread-safe.
#include <array>

#include "lanes.hpp"
#include "tumble/math.hpp"

namespace tumble::elliptic {

/// Longest increment λt the step's short form (increment_flow) handles: below K (≥ π/2) so
/// that Π(τ) has Carlson's form, and at most five doublings in jacobi_near_zero.
inline constexpr double kMaxIncrement = 1.0;

/// The Jacobi elliptic functions at one argument.
template <class T>
struct Jacobi {
  T sn, cn, dn;
};

/// A general box's flow once reduced to the elliptic case: the body momentum m0 in canonical
/// axes (kg·m²/s, m0[2] > 0, m0[0]² + m0[1]² > 0), the moments J1 < J2 < J3 or J1 > J2 > J3
/// (kg·m²), D_i = ±(M² − 2E J_i) > 0, and the signed permutation (perm, sgn) from body axes.
struct Case {
  Vec3 m0;
  double J1, J2, J3, D1, D2, D3;
  std::array<int, 3> perm;
  std::array<double, 3> sgn;
};

/// What the rotation is assembled from: the scalars of P(m(t)) and of W's second row
/// (frame_scalars), cos ψ and sin ψ, and 1/|m0|.
template <class T>
struct PhaseOf {
  T m[3];      ///< m(t) in canonical axes, kg·m²/s.
  T inv_rho;   ///< 1/ρ, ρ = √(m1² + m2²) of m(t).
  T rho;       ///< ρ of m(t).
  T z;         ///< m3 / (|m| ρ) of m(t).
  T inv_rho0;  ///< 1/ρ of m0.
  T cos_psi, sin_psi, inv_M;
};
using Phase = PhaseOf<double>;

/// D1 = M² − 2E J1, D2 = M² − 2E J2 and D3 = 2E J3 − M² of body momentum m (canonical
/// axes) and moments J, each a sum of terms m_i²/J_i (J_k − J_i) of one sign.
template <class T>
[[gnu::always_inline]] inline void differences(T m1, T m2, T m3, T J1, T J2, T J3, T& D1, T& D2,
                                               T& D3) {
  const T q1 = m1 * m1 / J1, q2 = m2 * m2 / J2, q3 = m3 * m3 / J3;
  D3 = q1 * (J3 - J1) + q2 * (J3 - J2);
  D1 = q2 * (J2 - J1) + q3 * (J3 - J1);
  D2 = q1 * (J1 - J2) + q3 * (J3 - J2);
}

/// Whether the canonical momentum is a steady spin about axis 3 (no polhode to follow).
template <class T>
[[gnu::always_inline]] inline auto steady_about_3(T m1, T m2, T J1, T J3, T D3) {
  return (D3 / (J3 - J1) <= 0.0) | (m1 * m1 + m2 * m2 == 0.0);
}

/// The polhode in canonical axes: amplitudes a_i, rate λ (1/s), k², k'², n, s, σ1, and sn,
/// cn, dn of the start phase u0, read off m0 (m1 = σ1 a1 cn u0, m2 = σ1 s a2 sn u0). On the
/// separatrix cn = sech > 0, so there σ1 = −1 maps (m1, m2) to (−m1, −m2) when m1 < 0.
template <class T>
struct Polhode {
  T a1, a2, a3, lambda, k2, kc2, n, s, sigma1;
  Jacobi<T> start;
};

template <class T>
[[gnu::always_inline]] inline Polhode<T> make_polhode(T m1, T m2, T J1, T J2, T J3, T D1, T D2,
                                                      T D3) {
  Polhode<T> p;
  const T r31 = 1.0 / (J3 - J1), r32 = 1.0 / (J3 - J2), r32d1 = r32 / D1;
  p.a1 = root(J1 * D3 * r31);
  p.a2 = root(J2 * D3 * r32);
  p.a3 = root(J3 * D1 * r31);
  p.lambda = root((J3 - J2) * D1 / (J1 * J2 * J3));
  const T k2 = (J2 - J1) * D3 * r32d1, kc2 = (J3 - J1) * D2 * r32d1;
  p.k2 = pick(k2 < 1.0, k2, splat<T>(1.0));    // std::min(1.0, k2)
  p.kc2 = pick(0.0 < kc2, kc2, splat<T>(0.0));  // std::max(0.0, kc2)
  p.n = -J3 * (J2 - J1) * r32 / J1;
  p.s = pick(J3 > J2, splat<T>(1.0), splat<T>(-1.0));
  p.sigma1 = pick((p.kc2 == 0.0) & (m1 < 0.0), splat<T>(-1.0), splat<T>(1.0));
  const T x = p.sigma1 * m1 / p.a1, y = p.sigma1 * p.s * m2 / p.a2;
  const T inv_h = 1.0 / root(x * x + y * y);  // 1 up to round-off
  p.start.sn = y * inv_h;
  p.start.cn = x * inv_h;
  // dn² = cn² + k'² sn² has no cancellation, unlike 1 − k² sn² near u = K, k → 1.
  p.start.dn = root(p.start.cn * p.start.cn + p.kc2 * p.start.sn * p.start.sn);
  return p;
}

/// sn, cn, dn at |u| ≤ 1/32 by their Maclaurin series (DLMF 22.10.4–6; the u⁸ and u⁹
/// coefficients checked against mpmath's Taylor coefficients): the first omitted term is below
/// 0.011 |u|¹⁰ ≈ 1e-17.
template <class T>
[[gnu::always_inline]] inline Jacobi<T> jacobi_series(T u, T k2) {
  constexpr double f3 = 1.0 / 6.0, f4 = 1.0 / 24.0, f5 = 1.0 / 120.0, f6 = 1.0 / 720.0,
                   f7 = 1.0 / 5040.0, f8 = 1.0 / 40320.0, f9 = 1.0 / 362880.0;  // 1/j!
  const T u2 = u * u, k4 = k2 * k2, k6 = k4 * k2;
  Jacobi<T> f;
  f.sn = u * (1.0 + u2 * (-(1.0 + k2) * f3 +
                          u2 * ((1.0 + 14.0 * k2 + k4) * f5 +
                                u2 * (-(1.0 + 135.0 * k2 + 135.0 * k4 + k6) * f7 +
                                      u2 * (1.0 + 1228.0 * k2 + 5478.0 * k4 + 1228.0 * k6 +
                                            k4 * k4) * f9))));
  f.cn = 1.0 + u2 * (-0.5 + u2 * ((1.0 + 4.0 * k2) * f4 +
                                  u2 * (-(1.0 + 44.0 * k2 + 16.0 * k4) * f6 +
                                        u2 * (1.0 + 408.0 * k2 + 912.0 * k4 + 64.0 * k6) * f8)));
  f.dn = 1.0 + u2 * k2 * (-0.5 + u2 * ((4.0 + k2) * f4 +
                                       u2 * (-(16.0 + 44.0 * k2 + k4) * f6 +
                                             u2 * (64.0 + 912.0 * k2 + 408.0 * k4 + k6) * f8)));
  return f;
}

/// sn, cn, dn at 2u from those at u: sn 2u = 2 s c d / (1 − k² s⁴),
/// cn 2u = (c² − s² d²) / (1 − k² s⁴), dn 2u = (d² − k² s² c²) / (1 − k² s⁴) (DLMF 22.8.1–3).
template <class T>
[[gnu::always_inline]] inline Jacobi<T> jacobi_doubled(const Jacobi<T>& f, T k2) {
  const T s2 = f.sn * f.sn, c2 = f.cn * f.cn, d2 = f.dn * f.dn;
  const T inv = 1.0 / (1.0 - k2 * s2 * s2);
  return {2.0 * f.sn * f.cn * f.dn * inv, (c2 - s2 * d2) * inv, (d2 - k2 * s2 * c2) * inv};
}

/// sn, cn, dn at u0 + τ from those at u0 (p.start) and at τ (f1), and s01 = sn u0 sn τ
/// (DLMF 22.8.1–2; dn from cn and sn, dn² = cn² + k'² sn², not the third addition formula:
/// this puts m(t) on the energy surface with M² − 2E J2 exact to relative round-off).
template <class T>
[[gnu::always_inline]] inline Jacobi<T> jacobi_added(const Polhode<T>& p, const Jacobi<T>& f1,
                                                     T& s01) {
  const Jacobi<T>& f0 = p.start;
  s01 = f0.sn * f1.sn;
  const T inv = 1.0 / (1.0 - p.k2 * s01 * s01);
  Jacobi<T> f;
  f.sn = (f0.sn * f1.cn * f1.dn + f1.sn * f0.cn * f0.dn) * inv;
  f.cn = (f0.cn * f1.cn - s01 * f0.dn * f1.dn) * inv;
  f.dn = root(f.cn * f.cn + p.kc2 * f.sn * f.sn);
  return f;
}

/// Carlson's R_J ends its duplications once the arguments' spread is below this fraction of
/// their mean, (2⁻⁵³ / 4)^(1/6): the fifth-order Taylor polynomial is then exact to 2⁻⁵³.
inline constexpr double kSpreadForSeries = 1.7e-3;

/// Carlson's R_C(1, 1 + e) by its alternating series Σ (−e)ʲ/(2j + 1) to e⁵, exact to
/// round-off for |e| < 1e-3 (the first omitted term is below e⁶/13).
template <class T>
[[gnu::always_inline]] inline T rc1_series(T e) {
  constexpr double c3 = 1.0 / 3.0, c5 = 1.0 / 5.0, c7 = 1.0 / 7.0, c9 = 1.0 / 9.0,
                   c11 = 1.0 / 11.0;
  return 1.0 + e * (-c3 + e * (c5 + e * (-c7 + e * (c9 - e * c11))));
}

/// One duplication of Carlson's R_J (x, y, z, p ← (· + λ)/4): returns λ and, in d,
/// (√p + √x)(√p + √y)(√p + √z).
template <class T>
[[gnu::always_inline]] inline T rj_duplication(T x, T y, T z, T p, T& d) {
  const T sx = root(x), sy = root(y), sz = root(z), sp = root(p);
  d = (sp + sx) * (sp + sy) * (sp + sz);
  return sx * sy + sx * sz + sy * sz;
}

/// R_J's end: the fifth-order Taylor polynomial about the mean a of the duplicated arguments
/// (Carlson, Numer. Algorithms 10, 1995), plus 6 Σ of the duplications' R_C terms.
template <class T>
[[gnu::always_inline]] inline T rj_tail(T x, T y, T z, T a0, T a, T scale, T sum) {
  const T inv = scale / a;
  const T X = (a0 - x) * inv, Y = (a0 - y) * inv, Z = (a0 - z) * inv;
  const T P = -0.5 * (X + Y + Z);
  const T xyz = X * Y * Z, P2 = P * P;
  const T E2 = X * Y + X * Z + Y * Z - 3.0 * P2;
  const T E3 = xyz + 2.0 * E2 * P + 4.0 * P2 * P;
  const T E4 = (2.0 * xyz + E2 * P + 3.0 * P2 * P) * P;
  const T E5 = xyz * P2;
  constexpr double c2 = 3.0 / 14.0, c3 = 1.0 / 6.0, c22 = 9.0 / 88.0, c4 = 3.0 / 22.0,
                   c23 = 9.0 / 52.0, c5 = 3.0 / 26.0;
  const T series = 1.0 - c2 * E2 + c3 * E3 + c22 * E2 * E2 - c4 * E4 - c23 * E2 * E3 + c5 * E5;
  return scale * series / (a * root(a)) + 6.0 * sum;
}

/// The increment's terms of the bracket (3/n)[Π(u) − u] over [u0, u0 + τ] (increment_flow in
/// free_rotation.cpp): w and z of the addition theorem of Π, and (f1.sn³ R_J, its first term).
template <class T>
[[gnu::always_inline]] inline T bracket_z(const Polhode<T>& p, const Jacobi<T>& f, T s01, T& w) {
  const T X = s01 * f.sn;
  const T A = 1.0 - p.n * (f.sn * f.sn - s01 * f.cn * f.dn);
  w = root(-p.n * (p.k2 - p.n) * (1.0 - p.n));
  return w * X / A;
}

/// The phase's scalars that P(m(t)) and W need, each behind a square root and a division:
/// m(t) = (σ1 a1 cn, σ1 s a2 sn, a3 dn) from sn, cn, dn at u0 + τ, its 1/ρ, ρ and z, and 1/ρ
/// of m0 = (m1, m2, ·). cos ψ, sin ψ are left to the caller.
template <class T>
[[gnu::always_inline]] inline PhaseOf<T> frame_scalars(const Polhode<T>& p, const Jacobi<T>& f,
                                                       T m1, T m2, T inv_M) {
  PhaseOf<T> r;
  r.m[0] = p.sigma1 * p.a1 * f.cn;
  r.m[1] = p.sigma1 * p.s * p.a2 * f.sn;
  r.m[2] = p.a3 * f.dn;
  const T rho2 = r.m[0] * r.m[0] + r.m[1] * r.m[1];
  r.inv_rho = 1.0 / root(rho2);
  r.rho = rho2 * r.inv_rho;
  r.z = r.m[2] * inv_M * r.inv_rho;
  r.inv_rho0 = 1.0 / root(m1 * m1 + m2 * m2);
  r.inv_M = inv_M;
  return r;
}

/// R(t)'s columns before the signed permutation C of assemble: column i of
/// W Rz(ψ) P(m(t)) with its sign sgn_i, which is R(t)'s column perm_i. W's columns come from
/// the world momentum L (kg·m²/s), c1 = R0 ê_perm0 and c2 = R0 ê_perm1, and m0's first two
/// components; col[i][r] is row r of column i.
template <class T>
[[gnu::always_inline]] inline void rotation_columns(const PhaseOf<T>& f, const T (&L)[3],
                                                    const T (&c1)[3], const T (&c2)[3], T m01,
                                                    T m02, const T (&sgn)[3], T (&col)[3][3]) {
  const T a = sgn[0] * m02, b = sgn[1] * m01;
  T w1[3], w2[3], w3[3];
  for (int k = 0; k < 3; ++k) {
    w3[k] = f.inv_M * L[k];
    w1[k] = f.inv_rho0 * (a * c1[k] - b * c2[k]);
  }
  w2[0] = w3[1] * w1[2] - w3[2] * w1[1];  // w3 × w1
  w2[1] = w3[2] * w1[0] - w3[0] * w1[2];
  w2[2] = w3[0] * w1[1] - w3[1] * w1[0];
  T w[3][3];  // W Rz(ψ), w[c][r]
  for (int k = 0; k < 3; ++k) {
    w[0][k] = f.cos_psi * w1[k] + f.sin_psi * w2[k];
    w[1][k] = f.cos_psi * w2[k] - f.sin_psi * w1[k];
    w[2][k] = w3[k];
  }
  // P(m(t)) by rows (momentum_frame): e1 = (m2, −m1, 0)/ρ, e2 = e3 × e1, e3 = m/|m|.
  const T* m = f.m;
  const T p[3][3] = {{m[1] * f.inv_rho, -m[0] * f.inv_rho, splat<T>(0.0)},
                     {m[0] * f.z, m[1] * f.z, -f.rho * f.inv_M},
                     {m[0] * f.inv_M, m[1] * f.inv_M, m[2] * f.inv_M}};
  for (int i = 0; i < 3; ++i) {
    const T q0 = sgn[i] * p[0][i], q1 = sgn[i] * p[1][i], q2 = sgn[i] * p[2][i];
    // The sums in the order Eigen 3.4's 3×3 product takes them (its last row starts from
    // the second term), so that R(t) keeps the bits it had as `w * p1c`.
    col[i][0] = w[0][0] * q0 + w[1][0] * q1 + w[2][0] * q2;
    col[i][1] = w[0][1] * q0 + w[1][1] * q1 + w[2][1] * q2;
    col[i][2] = w[1][2] * q1 + w[2][2] * q2 + w[0][2] * q0;
  }
}

/// ψ, the turn about L over t: M t / J1 + c · bracket, c = −M (J3 − J1)(J2 − J1) /
/// (3 λ J1² (J3 − J2)).
template <class T>
[[gnu::always_inline]] inline T psi_of(T M, double t, T J1, T J2, T J3, T lambda, T bracket) {
  const T c = -M * (J3 - J1) * (J2 - J1) / (3.0 * lambda * J1 * J1 * (J3 - J2));
  return M * t / J1 + c * bracket;
}

/// A body with three distinct moments: its body momentum Rᵀ L (kg·m²/s) and its axes by
/// increasing moment.
struct Start {
  Vec3 mb;
  std::array<int, 3> sorted;
};

/// The flow of a body with principal moments `inertia` (kg·m²), attitude R and world momentum
/// L (kg·m²/s) over t (s), first part: returns false with R(t) in `out` where it has a closed
/// form (no spin, a sphere-like body, regular precession), true with `st` otherwise.
bool reduce_start(const Vec3& inertia, const Mat3& R, const Vec3& L, double t, Mat3& out,
                  Start& st);

/// Second part: returns false with R(t) in `out` for a steady spin, true with the elliptic
/// case in `e` otherwise.
bool reduce_general(const Vec3& inertia, const Mat3& R, const Start& st, double t, Mat3& out,
                    Case& e);

/// The phase of the elliptic case `e` over t, one body (any t).
Phase phase(const Case& e, double t);

/// R(t) from the elliptic case's phase, the start attitude R0 and the world momentum L.
Mat3 assemble(const Case& e, const Phase& f, const Mat3& R0, const Vec3& L);

}  // namespace tumble::elliptic
