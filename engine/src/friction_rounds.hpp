#pragma once
/// The rounds of one floor impulse exchange (floor_impulse.cpp's `resolve`): the map G from
/// one round's friction to the next, Anderson mixing of its inputs, and Newton's method on
/// its fixed point for an exchange the rounds leave far off. Pure; thread-safe.
#include <array>

#include <Eigen/Core>

#include "active_set.hpp"
#include "floor_geometry.hpp"

namespace tumble::floor_detail {

/// One normal impulse or target per touching vertex (N·s, m/s).
using Impulses = std::array<double, kMaxPoints>;

/// Applies the active-set normal impulses (active_set.hpp) to s and k; returns them per
/// vertex.
inline Impulses solve_normal(BodyState& s, Kinematics& k, const ContactSet& set,
                             ActiveSetCache& system, const Impulses& target) {
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

/// What one round applies: the patch friction impulse F (N·s, along x and z) at `at` (m, from
/// the centre of mass) and the twist about the normal (N·m·s).
struct RoundInput {
  Eigen::Vector2d friction = Eigen::Vector2d::Zero();
  double twist = 0.0;
  Vec3 at = Vec3::Zero();
};

/// What a round finds: the next round's input G(x) and the Coulomb limit μ Σ jₙ of the loads
/// it was found at (N·s; 0: no load, the body leaves the floor, and `next` is not set).
struct RoundOutput {
  RoundInput next;
  double limit = 0.0;
};

/// The unknowns of the rounds as one vector (F_x, F_z, τ / r, at), N·s and m: the twist over
/// the body's bounding radius r (`lever`) shares the friction's units.
using RoundVector = Eigen::Matrix<double, 6, 1>;
/// x as a vector; the inverse of round_input.
inline RoundVector round_vector(const RoundInput& x, double lever) {
  RoundVector v;
  // Entry by entry: a 2-vector streamed into the 6-vector sent GCC's bounds check down an
  // AVX path that cannot run (-Warray-bounds).
  v << x.friction.x(), x.friction.y(), x.twist / lever, x.at.x(), x.at.y(), x.at.z();
  return v;
}

/// The input of vector v; the inverse of round_vector.
inline RoundInput round_input(const RoundVector& v, double lever) {
  return {v.head<2>(), lever * v(2), v.tail<3>()};
}

/// How far the output of a round moved from its input: |ΔF| + |Δτ| / lever, N·s.
inline double round_residual(const RoundInput& in, const RoundInput& out, double lever) {
  return (out.friction - in.friction).norm() + std::abs(out.twist - in.twist) / lever;
}

/// The map G of one exchange: a round applies its input to the state before the exchange,
/// solves the normal impulses, and takes as the next friction the impulse that cancels the
/// sliding at the loads' centroid through its 2×2 tangential mass, clamped to the cone
/// μ Σ jₙ, and as the next twist the one that stops the spin about the normal, clamped to
/// μ Σ jₙ times the loads' mean lever. Holds references to its arguments.
class FrictionRounds {
 public:
  FrictionRounds(const BodyState& s0, const Kinematics& k0, const ContactSet& set,
                 ActiveSetCache& system, const Impulses& target, double mu)
      : s0_(s0), k0_(k0), set_(set), system_(system), target_(target), mu_(mu) {}

  /// Applies `in` to the state before the exchange into s and k, then the normal impulses,
  /// which it returns.
  Impulses apply(const RoundInput& in, BodyState& s, Kinematics& k) const;
  /// G(in), from the normal impulses and kinematics that apply(in) left.
  RoundOutput read(const RoundInput& in, const Impulses& normal, const Kinematics& k) const;
  /// G(in) from the start: apply, then read.
  RoundOutput operator()(const RoundInput& in) const;

 private:
  const BodyState& s0_;
  const Kinematics& k0_;
  const ContactSet& set_;
  ActiveSetCache& system_;
  const Impulses& target_;
  double mu_;
};

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

/// Anderson mixing of depth 2 over the rounds' vectors.
class RoundMixer {
 public:
  /// The next round's input from this round's input x and output g = G(x).
  RoundVector next(const RoundVector& x, const RoundVector& g);

 private:
  int count_ = 0;  // rounds in the history since the last restart
  // The last round's residual and output, and their changes over the last two rounds.
  RoundVector f_ = RoundVector::Zero(), g_ = RoundVector::Zero();
  RoundVector df0_ = RoundVector::Zero(), dg0_ = RoundVector::Zero();
  RoundVector df1_ = RoundVector::Zero(), dg1_ = RoundVector::Zero();
};

/// The round of an exchange closest to its fixed point so far: its residual (round_residual,
/// N·s), its output and the limit it was found at.
struct ClosestRound {
  double residual = INFINITY;
  RoundInput output;
  double limit = 0.0;
};

/// Newton's method on G(x) = x from `best`'s output, a few steps; `best` takes any round
/// that comes closer to its fixed point.
void polish(const FrictionRounds& rounds, double lever, ClosestRound& best);

// A round runs these: inlined into resolve's loop, as they were before they had names (called,
// they cost the 300-cube μ = 1 landing 1.6 % more instructions in callgrind).

[[gnu::always_inline]] inline Impulses FrictionRounds::apply(const RoundInput& in, BodyState& s,
                                                             Kinematics& k) const {
  const Vec3 up = Vec3::UnitY();
  s = s0_;
  k = k0_;
  k.apply(s, in.at, Vec3(in.friction.x(), 0.0, in.friction.y()));
  s.L += in.twist * up;
  k.w += k.inv_inertia * (in.twist * up);
  return solve_normal(s, k, set_, system_, target_);
}

[[gnu::always_inline]] inline RoundOutput FrictionRounds::read(const RoundInput& in,
                                                               const Impulses& normal,
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

inline RoundVector RoundMixer::next(const RoundVector& x, const RoundVector& g) {
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

}  // namespace tumble::floor_detail
