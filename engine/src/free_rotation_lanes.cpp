/// free_rotation_exact for many bodies at once: the general boxes' elliptic flows (the
/// reduction to the elliptic case, the phase, the rotation) four at a time, one per SIMD lane
/// (lanes.hpp), each lane with the scalar's bits.
///
/// Why: a general box's exact step is a chain of about twenty square roots and divisions
/// (the polhode's amplitudes and rate, the Jacobi functions' doublings, Carlson's R_J), each
/// waiting on the one before; one body at a time the core idles through their latencies. Four
/// bodies side by side fill those waits with each other's work, as Box2D v3 and Box3D run
/// their contacts' constraint rows four or eight to a register. The lanes follow the scalar
/// code operation for operation (the formulas are elliptic_flow.hpp's templates; each loop
/// runs a lane as often as the scalar would run it), so a body gets the same bits in a lane
/// as alone. A lane that would leave the short form (an increment longer than
/// kMaxIncrement, an argument outside a series' range) or is a steady spin is computed again
/// alone.
#include <array>

#include "elliptic_flow.hpp"
#include "free_rotation.hpp"
#include "lanes.hpp"
#include "rotation_series.hpp"

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
// alone and put back in their lanes.
elliptic::PhaseOf<Lanes> phases(const std::array<const elliptic::Case*, 4>& e, double t) {
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
  elliptic::PhaseOf<Lanes> r = elliptic::frame_scalars(p, f, m1, m2, 1.0 / M);
  r.sin_psi = a * psi;
  r.cos_psi = 1.0 - b * (psi * psi);
  for (int i = 0; i < 4; ++i) {
    if (!fail[i]) continue;
    const elliptic::Phase alone = elliptic::phase(*e[i], t);
    for (int k = 0; k < 3; ++k) r.m[k][i] = alone.m[k];
    r.inv_rho[i] = alone.inv_rho;
    r.rho[i] = alone.rho;
    r.z[i] = alone.z;
    r.inv_rho0[i] = alone.inv_rho0;
    r.cos_psi[i] = alone.cos_psi;
    r.sin_psi[i] = alone.sin_psi;
    r.inv_M[i] = alone.inv_M;
  }
  return r;
}

// R(t) of four cases from their phases (elliptic::assemble in lanes): each lane's columns
// go to the places its permutation gives them.
void assemble(const std::array<const elliptic::Case*, 4>& e,
              const std::array<const FreeFlow*, 4>& flows, int n,
              const elliptic::PhaseOf<Lanes>& f) {
  Lanes L[3], c1[3], c2[3], sgn[3], m01, m02;
  for (int i = 0; i < 4; ++i) {
    const elliptic::Case& c = *e[i];
    const Mat3& R0 = *flows[i]->R;
    for (int k = 0; k < 3; ++k) {
      L[k][i] = (*flows[i]->L)[k];
      c1[k][i] = R0(k, c.perm[0]);
      c2[k][i] = R0(k, c.perm[1]);
      sgn[k][i] = c.sgn[k];
    }
    m01[i] = c.m0[0];
    m02[i] = c.m0[1];
  }
  Lanes col[3][3];
  elliptic::rotation_columns(f, L, c1, c2, m01, m02, sgn, col);
  for (int i = 0; i < n; ++i) {
    Mat3& out = *flows[i]->out;
    for (int k = 0; k < 3; ++k)
      out.col(e[i]->perm[k]) = Vec3(col[k][0][i], col[k][1][i], col[k][2][i]);
  }
}

// The elliptic cases waiting for their phases, four to a batch.
class PhaseBatch {
 public:
  explicit PhaseBatch(double t) : t_(t) {}

  // Queues flow f's case; runs the batch once it holds four.
  void add(const elliptic::Case& e, const FreeFlow& f) {
    cases_[n_] = e;
    flows_[n_++] = &f;
    if (n_ == 4) run();
  }

  // Runs what is queued: a lone case alone, two or three in lanes (the unused ones repeat
  // the first).
  void run() {
    if (n_ == 1) {
      *flows_[0]->out = elliptic::assemble(cases_[0], elliptic::phase(cases_[0], t_),
                                           *flows_[0]->R, *flows_[0]->L);
    } else if (n_ > 1) {
      std::array<const elliptic::Case*, 4> lanes;
      std::array<const FreeFlow*, 4> flows;
      for (int i = 0; i < 4; ++i) {
        lanes[i] = &cases_[i < n_ ? i : 0];
        flows[i] = flows_[i < n_ ? i : 0];
      }
      assemble(lanes, flows, n_, phases(lanes, t_));
    }
    n_ = 0;
  }

 private:
  double t_;
  std::array<elliptic::Case, 4> cases_;
  std::array<const FreeFlow*, 4> flows_;
  int n_ = 0;
};

// elliptic::reduce_general for n ≤ 4 started flows, in lanes (the unused ones repeat the
// first); steady spins, whose R(t) is a plain turn, are reduced alone. Each elliptic case
// goes to `batch`.
void reduce_general(const std::array<elliptic::Start, 4>& st,
                    const std::array<const FreeFlow*, 4>& flows, int n, double t,
                    PhaseBatch& batch) {
  Lanes lo, mid, hi, m_lo, m_mid, m_hi, odd_up, odd_down;
  for (int j = 0; j < 4; ++j) {
    const int i = j < n ? j : 0;
    const Vec3& inertia = *flows[i]->inertia;
    const std::array<int, 3>& a = st[i].sorted;
    lo[j] = inertia[a[0]];
    mid[j] = inertia[a[1]];
    hi[j] = inertia[a[2]];
    m_lo[j] = st[i].mb[a[0]];
    m_mid[j] = st[i].mb[a[1]];
    m_hi[j] = st[i].mb[a[2]];
    // Whether the canonical permutation is odd, for the sorted axes and for them reversed.
    odd_up[j] = (a[0] + 1) % 3 != a[1] ? -1.0 : 1.0;
    odd_down[j] = (a[2] + 1) % 3 != a[1] ? -1.0 : 1.0;
  }
  // M² − 2E·I_mid, from the two outer moments only.
  Lanes d_mid = splat<Lanes>(0.0) + m_lo * m_lo * (lo - mid) / lo;
  d_mid = d_mid + m_hi * m_hi * (hi - mid) / hi;
  // Canonical axes: 3 is the largest moment above the separatrix, the smallest below it.
  const LaneMask up = d_mid >= 0.0;
  const Lanes J1 = pick(up, lo, hi), J2 = mid, J3 = pick(up, hi, lo);
  const Lanes m1 = pick(up, m_lo, m_hi), m3 = pick(up, m_hi, m_lo);
  // Signs: m3 > 0, and axis 2 flipped once more for an odd permutation.
  const Lanes sgn3 = pick(m3 < 0.0, splat<Lanes>(-1.0), splat<Lanes>(1.0));
  const Lanes sgn2 = pick(pick(up, odd_up, odd_down) < 0.0, -sgn3, sgn3);
  const Lanes c1 = 1.0 * m1, c2 = sgn2 * m_mid, c3 = sgn3 * m3;
  Lanes D1, D2, D3;
  elliptic::differences(c1, c2, c3, J1, J2, J3, D1, D2, D3);
  const LaneMask steady =
      ((m1 == 0.0) & (m3 == 0.0)) | elliptic::steady_about_3(c1, c2, J1, J3, D3);
  for (int i = 0; i < n; ++i) {
    const FreeFlow& f = *flows[i];
    if (steady[i]) {
      elliptic::Case e;
      if (elliptic::reduce_general(*f.inertia, *f.R, st[i], t, *f.out, e)) batch.add(e, f);
      continue;
    }
    const std::array<int, 3>& a = st[i].sorted;
    const std::array<int, 3> perm = up[i] ? a : std::array<int, 3>{a[2], a[1], a[0]};
    batch.add({Vec3(c1[i], c2[i], c3[i]), J1[i], J2[i], J3[i], D1[i], D2[i], D3[i], perm,
               {1.0, sgn2[i], sgn3[i]}},
              f);
  }
}

}  // namespace

void free_rotation_exact_many(std::span<const FreeFlow> flows, double t) {
  PhaseBatch batch(t);
  std::array<elliptic::Start, 4> started;
  std::array<const FreeFlow*, 4> waiting;
  int n = 0;
  for (const FreeFlow& f : flows) {
    if (!elliptic::reduce_start(*f.inertia, *f.R, *f.L, t, *f.out, started[n])) continue;
    waiting[n++] = &f;
    if (n == 4) {
      reduce_general(started, waiting, n, t, batch);
      n = 0;
    }
  }
  if (n > 0) reduce_general(started, waiting, n, t, batch);
  batch.run();
}

}  // namespace tumble
