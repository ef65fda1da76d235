/// free_rotation_exact for many bodies at once: the general boxes' elliptic phases four at a
/// time, one per SIMD lane (lanes.hpp), each lane with the scalar's bits.
///
/// Why: a general box's exact step is a chain of about twenty square roots and divisions
/// (the polhode's amplitudes and rate, the Jacobi functions' doublings, Carlson's R_J), each
/// waiting on the one before; one body at a time the core idles through their latencies. Four
/// bodies side by side fill those waits with each other's work, as Box2D v3 and Box3D run
/// their contacts' constraint rows four or eight to a register. The lanes follow the scalar
/// code operation for operation (the formulas are elliptic_flow.hpp's templates; each loop
/// runs a lane as often as the scalar would run it), so a body gets the same bits in a lane
/// as alone. A lane that would leave the short form (an increment longer than
/// kMaxIncrement, an argument outside a series' range) is computed again alone.
#include <array>

#include "elliptic_flow.hpp"
#include "free_rotation.hpp"
#include "lanes.hpp"
#include "rotation_series.hpp"

#pragma GCC diagnostic ignored "-Wpsabi"  // Lanes never cross a call boundary outside this file

namespace tumble {
namespace {

using JacobiLanes = elliptic::Jacobi<Lanes>;

// Carlson's R_C(1, 1 + e) by its series; lanes of `active` outside the series' range
// (|e| ≥ 1e-3, or not a number) are marked in `fail`.
Lanes carlson_rc1(Lanes e, LaneMask active, LaneMask& fail) {
  fail |= active & ~(magnitude(e) < 1e-3);
  return elliptic::rc1_series(e);
}

// std::max({a, b, c, d}) lane by lane: the first of the largest, as max_element takes it.
Lanes largest(Lanes a, Lanes b, Lanes c, Lanes d) {
  Lanes m = pick(a < b, b, a);
  m = pick(m < c, c, m);
  return pick(m < d, d, m);
}

// carlson_rj of free_rotation.cpp: a lane duplicates while its own spread asks for it.
Lanes carlson_rj(Lanes x, Lanes y, Lanes z, Lanes p, LaneMask& fail) {
  const Lanes a0 = 0.2 * (x + y + z + 2.0 * p);
  const Lanes delta = (p - x) * (p - y) * (p - z);
  const Lanes spread =
      largest(magnitude(a0 - x), magnitude(a0 - y), magnitude(a0 - z), magnitude(a0 - p)) *
      (1.0 / elliptic::kSpreadForSeries);
  Lanes a = a0, scale = splat<Lanes>(1.0), sum = splat<Lanes>(0.0);
  Lanes xm = x, ym = y, zm = z, pm = p;
  for (int m = 0; m < 40; ++m) {
    const LaneMask go = scale * spread >= a;
    if (!any(go)) break;
    Lanes d;
    const Lanes lam = elliptic::rj_duplication(xm, ym, zm, pm, d);
    const Lanes term = scale * carlson_rc1(scale * scale * scale * delta / (d * d), go, fail) / d;
    sum = pick(go, sum + term, sum);
    a = pick(go, 0.25 * (a + lam), a);
    xm = pick(go, 0.25 * (xm + lam), xm);
    ym = pick(go, 0.25 * (ym + lam), ym);
    zm = pick(go, 0.25 * (zm + lam), zm);
    pm = pick(go, 0.25 * (pm + lam), pm);
    scale = pick(go, scale * 0.25, scale);
  }
  return elliptic::rj_tail(x, y, z, a0, a, scale, sum);
}

// jacobi_near_zero of free_rotation.cpp: each lane halves u and doubles back as often as the
// scalar would.
JacobiLanes jacobi_near_zero(Lanes u, Lanes k2) {
  LaneMask doublings = {0, 0, 0, 0};
  for (int i = 0; i < 8; ++i) {
    const LaneMask halve = magnitude(u) > 1.0 / 32.0;
    if (!any(halve)) break;
    u = pick(halve, u * 0.5, u);
    doublings -= halve;  // a mask is −1 where it holds
  }
  JacobiLanes f = elliptic::jacobi_series(u, k2);
  for (int i = 0; i < 8; ++i) {
    const LaneMask on = doublings > i;
    if (!any(on)) break;
    const JacobiLanes g = elliptic::jacobi_doubled(f, k2);
    f = {pick(on, g.sn, f.sn), pick(on, g.cn, f.cn), pick(on, g.dn, f.dn)};
  }
  return f;
}

// increment_flow of free_rotation.cpp.
JacobiLanes increment_flow(const elliptic::Polhode<Lanes>& p, Lanes tau, Lanes& bracket,
                           LaneMask& fail) {
  const JacobiLanes f1 = jacobi_near_zero(tau, p.k2);
  Lanes s01, w;
  const JacobiLanes f = elliptic::jacobi_added(p, f1, s01);
  const Lanes rj = carlson_rj(f1.cn * f1.cn, f1.dn * f1.dn, splat<Lanes>(1.0),
                              1.0 - p.n * f1.sn * f1.sn, fail);
  const Lanes z = elliptic::bracket_z(p, f, s01, w);
  const LaneMask all = {-1, -1, -1, -1};
  bracket = f1.sn * f1.sn * f1.sn * rj + 3.0 * z * carlson_rc1(z * z, all, fail) / w;
  return f;
}

// elliptic::phase for four cases over t; lanes the short form cannot take are computed
// alone.
void phases(const std::array<const elliptic::Case*, 4>& e, double t,
            std::array<elliptic::Phase, 4>& out) {
  Lanes m1, m2, J1, J2, J3, D1, D2, D3, M;
  for (int i = 0; i < 4; ++i) {
    const elliptic::Case& c = *e[i];
    m1[i] = c.m0[0];
    m2[i] = c.m0[1];
    J1[i] = c.J1;
    J2[i] = c.J2;
    J3[i] = c.J3;
    D1[i] = c.D1;
    D2[i] = c.D2;
    D3[i] = c.D3;
    M[i] = c.m0.norm();
  }
  const elliptic::Polhode<Lanes> p = elliptic::make_polhode(m1, m2, J1, J2, J3, D1, D2, D3);
  const Lanes tau = p.lambda * t;
  LaneMask fail = ~(magnitude(tau) <= elliptic::kMaxIncrement);
  Lanes bracket;
  const JacobiLanes f = increment_flow(p, tau, bracket, fail);
  const Lanes psi = elliptic::psi_of(M, t, J1, J2, J3, p.lambda, bracket);
  // small_angle_sin_cos, whose sinc_and_versine takes its series below ψ² = 0.25.
  const Lanes psi2 = psi * psi;
  fail |= ~(psi2 < 0.25);
  Lanes a, b;
  sinc_versine_series(psi2, a, b);
  const Lanes sin_psi = a * psi, cos_psi = 1.0 - b * (psi * psi);
  const elliptic::PhaseOf<Lanes> r = elliptic::frame_scalars(p, f, m1, m2, 1.0 / M);
  for (int i = 0; i < 4; ++i) {
    if (fail[i]) {
      out[i] = elliptic::phase(*e[i], t);
      continue;
    }
    out[i] = {{r.m[0][i], r.m[1][i], r.m[2][i]}, r.inv_rho[i], r.rho[i], r.z[i], r.inv_rho0[i],
              cos_psi[i], sin_psi[i], r.inv_M[i]};
  }
}

// R(t) of the n ≤ 4 pending elliptic cases (the unused lanes repeat the first).
void finish(const std::array<elliptic::Case, 4>& cases,
            const std::array<const FreeFlow*, 4>& pending, int n, double t) {
  std::array<const elliptic::Case*, 4> lanes;
  for (int i = 0; i < 4; ++i) lanes[i] = &cases[i < n ? i : 0];
  std::array<elliptic::Phase, 4> ph;
  phases(lanes, t, ph);
  for (int i = 0; i < n; ++i)
    *pending[i]->out = elliptic::assemble(cases[i], ph[i], *pending[i]->R, *pending[i]->L);
}

}  // namespace

void free_rotation_exact_many(std::span<const FreeFlow> flows, double t) {
  std::array<elliptic::Case, 4> cases;
  std::array<const FreeFlow*, 4> pending;
  int n = 0;
  for (const FreeFlow& f : flows) {
    if (!elliptic::reduce(*f.inertia, *f.R, *f.L, t, *f.out, cases[n])) continue;
    pending[n++] = &f;
    if (n == 4) {
      finish(cases, pending, n, t);
      n = 0;
    }
  }
  if (n == 1) {
    *pending[0]->out = elliptic::assemble(cases[0], elliptic::phase(cases[0], t), *pending[0]->R,
                                          *pending[0]->L);
  } else if (n > 1) {
    finish(cases, pending, n, t);
  }
}

}  // namespace tumble
