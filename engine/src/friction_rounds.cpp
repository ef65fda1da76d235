#include "friction_rounds.hpp"

#include <Eigen/QR>

namespace tumble::floor_detail {

Impulses solve_normal(BodyState& s, Kinematics& k, const ContactSet& set, ActiveSetCache& system,
                      const Impulses& target) {
  const int n = set.count;
  PointVector vn(n), goal(n);
  for (int i = 0; i < n; ++i) vn(i) = k.point_velocity(set.r[i]).y(), goal(i) = target[i];
  const PointVector impulse = solve_active_set(system, vn, goal);
  Impulses applied{};
  for (int i = 0; i < n; ++i) {
    if (impulse(i) <= 0.0) continue;
    k.apply(s, set.r[i], impulse(i) * Vec3::UnitY());
    applied[i] = impulse(i);
  }
  return applied;
}

RoundVector round_vector(const RoundInput& x, double lever) {
  RoundVector v;
  // Entry by entry: a 2-vector streamed into the 6-vector sent GCC's bounds check down an
  // AVX path that cannot run (-Warray-bounds).
  v << x.friction.x(), x.friction.y(), x.twist / lever, x.at.x(), x.at.y(), x.at.z();
  return v;
}

RoundInput round_input(const RoundVector& v, double lever) {
  return {v.head<2>(), lever * v(2), v.tail<3>()};
}

double round_residual(const RoundInput& in, const RoundInput& out, double lever) {
  return (out.friction - in.friction).norm() + std::abs(out.twist - in.twist) / lever;
}

Impulses FrictionRounds::apply(const RoundInput& in, BodyState& s, Kinematics& k) const {
  const Vec3 up = Vec3::UnitY();
  s = s0_;
  k = k0_;
  k.apply(s, in.at, Vec3(in.friction.x(), 0.0, in.friction.y()));
  s.L += in.twist * up;
  k.w += k.inv_inertia * (in.twist * up);
  return solve_normal(s, k, set_, system_, target_);
}

RoundOutput FrictionRounds::read(const RoundInput& in, const Impulses& normal,
                                 const Kinematics& k) const {
  double total = 0.0;
  Vec3 centroid = Vec3::Zero();
  for (int i = 0; i < set_.count; ++i) total += normal[i], centroid += normal[i] * set_.r[i];
  if (total <= 0.0) return {};
  centroid /= total;
  double radius = 0.0;  // load-weighted mean distance from the centroid in the floor plane
  for (int i = 0; i < set_.count; ++i) {
    const Vec3 d = set_.r[i] - centroid;
    radius += normal[i] * std::hypot(d.x(), d.z());
  }
  radius /= total;
  const Mat3 rx = skew(centroid);
  const Mat3 mass3 = k.inv_mass * Mat3::Identity() - rx * k.inv_inertia * rx;
  Eigen::Matrix2d kt;
  kt << mass3(0, 0), mass3(0, 2), mass3(2, 0), mass3(2, 2);
  const Vec3 u = k.point_velocity(centroid);
  const double limit = mu_ * total;
  Eigen::Vector2d next = in.friction - kt.inverse() * Eigen::Vector2d(u.x(), u.z());
  if (next.norm() > limit) next *= limit / next.norm();
  // Torsional friction of the patch: a face spinning on the floor is braked by at most
  // μ N times the mean lever of its load; a single point contact has none.
  double next_twist = in.twist - k.w.y() / k.inv_inertia(1, 1);
  next_twist = std::clamp(next_twist, -limit * radius, limit * radius);
  return {{next, next_twist, centroid}, limit};
}

RoundOutput FrictionRounds::operator()(const RoundInput& in) const {
  BodyState s;
  Kinematics k;
  const Impulses normal = apply(in, s, k);
  return read(in, normal, k);
}

// The rounds are a fixed-point iteration x = G(x) on x = (F_x, F_z, τ / r, c): the patch's
// friction impulse, its twist (over the body's bounding radius r, to share units) and the
// point c where F is applied, the centroid of the normal impulses it was found at. Plain, they
// converge linearly: a box sticking on an edge loses about 60 % of its error a round; one
// sliding along the edge sits on its cone μ Σ jₙ while the load swings from one vertex to the
// other and back (a ratio near −0.7) or piles onto one of them (+0.8). Aitken's Δ² on each
// unknown alone (the rule until 2026-11-28) took only ratios in (0, 0.9) and left a quarter of
// a μ = 1 landing's edge exchanges 1e-3–1e-2 of the friction impulse from the fixed point
// after 16 rounds.
//
// Anderson mixing of depth 2 (Anderson 1965; Walker & Ni, SIAM J. Numer. Anal. 49, 2011)
// takes as the next input the combination of the last three outputs g whose residuals
// f = G(x) − x cancel best in least squares, a 2×2 system here: it solves a linear map of two
// modes exactly, whatever their signs. It needs c among the unknowns: mixed on (F, τ / r)
// alone, the next round applied the mixed F at the new centroid, a point the mixing never
// saw, so the map it extrapolated changed under it, and 30 % of sliding-edge exchanges never
// settled. A residual that grows more than twofold restarts the history (the map has kinks:
// the normal solve's active set, the cone, a vertex whose load goes to zero).
RoundVector RoundMixer::next(const RoundVector& x, const RoundVector& g) {
  const RoundVector f = g - x;
  if (count_ > 0 && f.squaredNorm() > 4.0 * f_.squaredNorm()) count_ = 0;
  if (count_ > 0) {
    df1_ = df0_, dg1_ = dg0_;
    df0_ = f - f_, dg0_ = g - g_;
  }
  f_ = f, g_ = g;
  const int depth = std::min(count_++, 2);
  const double a00 = depth > 0 ? df0_.squaredNorm() : 0.0;
  if (a00 == 0.0) return g;
  const double b0 = df0_.dot(f);
  if (depth == 2) {
    const double a01 = df0_.dot(df1_), a11 = df1_.squaredNorm();
    const double det = a00 * a11 - a01 * a01;
    if (det > 1e-12 * a00 * a11) {  // the two changes are not (nearly) parallel
      const double b1 = df1_.dot(f);
      return g - ((a11 * b0 - a01 * b1) / det) * dg0_ - ((a00 * b1 - a01 * b0) / det) * dg1_;
    }
  }
  return g - (b0 / a00) * dg0_;
}

// Newton's method on f(x) = G(x) − x, with f's Jacobian by forward differences (six rounds)
// and a step halved until |f| falls. G is smooth between its kinks, so near a fixed point
// that is not on one a step takes the residual from 1e-5 to round-off, where the rounds gain
// a factor of two or three each. On a kink the differences straddle it and Newton stalls; the
// rounds before have crept as close as they can, and `best` keeps the closer of the two.
// Measured on the 3,000 sliding edges of the friction tests and a 1,000-cube landing at
// μ = 1 (docs/engine.md, "What changed").
void polish(const FrictionRounds& rounds, double lever, ClosestRound& best) {
  constexpr int kSteps = 3;      // Newton steps at most
  constexpr int kHalvings = 4;   // tries of each step, halved each time
  constexpr double kDiff = 1e-7;  // the differences' step, relative to the unknown's scale
  RoundVector x = round_vector(best.output, lever);
  RoundOutput out = rounds(best.output);
  if (out.limit <= 0.0) return;
  RoundVector f = round_vector(out.next, lever) - x;
  for (int step = 0; step < kSteps; ++step) {
    Eigen::Matrix<double, 6, 6> jacobian;
    for (int i = 0; i < 6; ++i) {
      const double scale = i < 3 ? out.limit : lever;  // N·s for F and τ / r, m for c
      const double h = kDiff * std::max(std::abs(x(i)), scale);
      RoundVector xi = x;
      xi(i) += h;
      const RoundOutput oi = rounds(round_input(xi, lever));
      if (oi.limit <= 0.0) return;
      jacobian.col(i) = (round_vector(oi.next, lever) - xi - f) / h;
    }
    const RoundVector dx = jacobian.colPivHouseholderQr().solve(-f);
    bool fell = false;
    double t = 1.0;
    for (int k = 0; k < kHalvings && !fell; ++k, t *= 0.5) {
      const RoundVector xt = x + t * dx;
      const RoundOutput ot = rounds(round_input(xt, lever));
      if (ot.limit <= 0.0) continue;
      const RoundVector ft = round_vector(ot.next, lever) - xt;
      if (ft.squaredNorm() >= f.squaredNorm()) continue;
      x = xt, f = ft, out = ot, fell = true;
    }
    if (!fell) return;
    const double residual = round_residual(round_input(x, lever), out.next, lever);
    if (residual < best.residual) best = {residual, out.next, out.limit};
    if (residual <= 1e-13 * out.limit) return;
  }
}

}  // namespace tumble::floor_detail
