#include "floor_impulse.hpp"

#include <Eigen/Cholesky>

namespace tumble::floor_detail {
namespace {

/// The contacts' normal-impulse system K = D S Dᵀ (active_set.hpp); I⁻¹ is fixed within one
/// impulse exchange.
NormalSystem normal_system(const Kinematics& k, const ContactSet& set) {
  Vec3 origin = Vec3::Zero();
  for (int i = 0; i < set.count; ++i) origin += set.r[i];
  origin /= set.count;
  std::array<Vec3, kMaxPoints> offsets;
  for (int i = 0; i < set.count; ++i) offsets[i] = set.r[i] - origin;
  const ContactSide body{k.inv_mass, k.inv_inertia, origin};
  return make_normal_system(Vec3::UnitY(), Vec3::UnitX(), Vec3::UnitZ(), offsets.data(),
                            set.count, nullptr, &body);
}

/// Applies the active-set normal impulses (active_set.hpp) and returns them per contact.
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

// A body on one vertex that sticks: the impulse j that leaves the vertex with the normal
// target and no sliding solves the 3×3 system K j = Δv, K = m⁻¹ I − [r]× I⁻¹ [r]× (the
// point's mass matrix), exactly. The alternating friction/normal rounds below reach the same
// j only linearly (a ratio of about 0.4 a round: 16 rounds without 1e-13, for most vertices
// of a landing at μ = 1). Returns false, touching nothing, when that j would pull or leave
// the friction cone: the vertex slides and the rounds decide.
bool stick_on_one_vertex(const BodyState& s0, const Kinematics& k0, const Vec3& r,
                         double normal_target, double mu, BodyState& s, PatchFriction* patch) {
  const Mat3 rx = skew(r);
  const Mat3 K = k0.inv_mass * Mat3::Identity() - rx * k0.inv_inertia * rx;
  const Vec3 v = k0.point_velocity(r);
  const Vec3 j = K.ldlt().solve(Vec3(-v.x(), normal_target - v.y(), -v.z()));
  if (!(j.y() >= 0.0) || std::hypot(j.x(), j.z()) > mu * j.y()) return false;
  s = s0;
  Kinematics k = k0;
  k.apply(s, r, j);
  if (patch) *patch = {std::hypot(j.x(), j.z()), mu * j.y()};
  return true;
}

// The rounds below are a fixed-point iteration x = G(x) on x = (F_x, F_z, τ / r, c): the
// patch's friction impulse, its twist (over the body's bounding radius r, to share units) and
// the point c where F is applied, the centroid of the normal impulses it was found at. Plain,
// they converge linearly: a box sticking on an edge loses about 60 % of its error a round; one
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
// settled. Three guards, as the method needs on a map with kinks (the normal solve's active
// set, the cone, a vertex whose load goes to zero): a residual that grows more than twofold
// restarts the history; after kMixedRounds the rounds go on plain (for an exchange still far
// from its fixed point), as mixing can circle a kink where plain rounds creep in; and the last
// round applies the output of the round that came closest to its fixed point, so what is left
// in the patch is always inside its cone. The answer is still the rounds' own fixed point.
class RoundMixer {
 public:
  /// The unknowns (F_x, F_z, τ / r, c), N·s and m.
  using Vector = Eigen::Matrix<double, 6, 1>;
  /// The next round's input from this round's input x and output g = G(x).
  Vector next(const Vector& x, const Vector& g) {
    const Vector f = g - x;
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

 private:
  int count_ = 0;  // rounds in the history since the last restart
  // The last round's residual and output, and their changes over the last two rounds.
  Vector f_ = Vector::Zero(), g_ = Vector::Zero();
  Vector df0_ = Vector::Zero(), dg0_ = Vector::Zero();
  Vector df1_ = Vector::Zero(), dg1_ = Vector::Zero();
};

}  // namespace

/// Normal velocity each contact should leave with if it is pushed: −eᵢ v⁻ₙ for an approaching
/// contact (e = 0 below the rest speed, which ends a Zeno series), 0 for a resting one.
Impulses normal_targets(const Kinematics& k, const ContactSet& set, double e,
                        double rest_speed_ms) {
  Impulses target{};
  for (int i = 0; i < set.count; ++i) {
    const double vn = k.point_velocity(set.r[i]).y();
    const double ei = (e * -vn < rest_speed_ms) ? 0.0 : e;
    target[i] = vn < 0.0 ? -ei * vn : 0.0;
  }
  return target;
}

// Coulomb friction on the contact patch as a whole, alternated with the exact normal solve
// to a fixed point: the tangential impulse F acts at the normal-impulse-weighted centroid of
// the contacts, cancels the sliding velocity there through its 2×2 tangential mass, and is
// clamped to the cone |F| ≤ μ Σ jₙ (Stewart & Trinkle 1996 reduce to this for one patch).
// Each round re-solves the normal impulses from the state before the impulse exchange, so the
// load shifts to the leading edge of a sliding box instead of tipping it, and a flat slide
// decelerates at exactly μ g.
int resolve(BodyState& s, const BodyConstants& c, const ContactSet& set, const Impulses& target,
            double mu, PatchFriction* patch) {
  if (set.count == 0) return 0;
  const BodyState s0 = s;
  const Kinematics k0 = kinematics_of(s, c);
  // A vertex that sticks takes its impulse from the state before the exchange, whatever the
  // normal solve would have applied: that solve is needed only when it slides.
  if (mu > 0.0 && set.count == 1 &&
      stick_on_one_vertex(s0, k0, set.r[0], target[0], mu, s, patch))
    return 1;
  Kinematics k = k0;
  const NormalSystem normal_sys = normal_system(k0, set);
  ActiveSetCache system(normal_sys);
  Impulses normal = solve_normal(s, k, set, system, target);
  if (mu <= 0.0) return set.count;
  Eigen::Vector2d friction = Eigen::Vector2d::Zero();
  double twist = 0.0;  // torsional impulse about the normal, N·m·s
  const Vec3 up = Vec3::UnitY();
  const double lever = c.bounding_radius;  // m: the twist's scale among the unknowns
  RoundMixer mixer;
  constexpr int kRounds = 32;       // at most; most exchanges settle within 3–10
  constexpr int kMixedRounds = 16;  // then plain rounds, for an exchange still far off:
  constexpr double kFarOff = 1e-7;  // its closest residual above this part of μ Σ jₙ
  // The output of the round closest to its fixed point (residual: |G(x) − x| over the
  // friction and the twist / r, N·s), applied if the rounds end unsettled.
  struct Closest {
    double residual = INFINITY;
    Eigen::Vector2d friction = Eigen::Vector2d::Zero();
    double twist = 0.0;
    Vec3 at = Vec3::Zero();
    double limit = 0.0;
  } closest;
  Vec3 applied_at = Vec3::Zero();  // where `friction` was applied
  for (int round = 0; round < kRounds; ++round) {
    double total = 0.0;
    Vec3 centroid = Vec3::Zero();
    for (int i = 0; i < set.count; ++i) total += normal[i], centroid += normal[i] * set.r[i];
    if (total <= 0.0) break;
    centroid /= total;
    if (round == 0) applied_at = centroid;  // no friction yet: where it was applied is moot
    double radius = 0.0;  // load-weighted mean distance from the centroid in the floor plane
    for (int i = 0; i < set.count; ++i) {
      const Vec3 d = set.r[i] - centroid;
      radius += normal[i] * std::hypot(d.x(), d.z());
    }
    radius /= total;
    const Mat3 rx = skew(centroid);
    const Mat3 mass3 = k.inv_mass * Mat3::Identity() - rx * k.inv_inertia * rx;
    Eigen::Matrix2d kt;
    kt << mass3(0, 0), mass3(0, 2), mass3(2, 0), mass3(2, 2);
    const Vec3 u = k.point_velocity(centroid);
    Eigen::Vector2d next = friction - kt.inverse() * Eigen::Vector2d(u.x(), u.z());
    if (next.norm() > mu * total) next *= mu * total / next.norm();
    // Torsional friction of the patch: a face spinning on the floor is braked by at most
    // μ N times the mean lever of its load; a single point contact has none.
    double next_twist = twist - k.w.y() / k.inv_inertia(1, 1);
    next_twist = std::clamp(next_twist, -mu * total * radius, mu * total * radius);
    const double moved = (next - friction).norm();
    const double turned = std::abs(next_twist - twist);
    const bool settled = moved <= 1e-13 * (1.0 + next.norm()) &&
                         turned <= 1e-13 * (1.0 + std::abs(next_twist));
    double residual = moved + turned / lever, limit = mu * total;
    if (!settled && residual < closest.residual)
      closest = {residual, next, next_twist, centroid, limit};
    // Plain rounds cost a tenth of a μ = 1 landing's time when every unsettled exchange took
    // them; most of those were creeping within 1e-7 of their fixed point already.
    const bool close_enough =
        round >= kMixedRounds - 1 && closest.residual <= kFarOff * closest.limit;
    Vec3 at = centroid;
    if (settled) {
      friction = next;
      twist = next_twist;
    } else if (round == kRounds - 1 || close_enough) {
      friction = closest.friction;
      twist = closest.twist;
      at = closest.at;
      residual = closest.residual;
      limit = closest.limit;
    } else {
      RoundMixer::Vector x, g;
      // Entry by entry: a 2-vector streamed into the 6-vector sent GCC's bounds check down an
      // AVX path that cannot run (-Warray-bounds).
      x << friction.x(), friction.y(), twist / lever, applied_at.x(), applied_at.y(),
          applied_at.z();
      g << next.x(), next.y(), next_twist / lever, centroid.x(), centroid.y(), centroid.z();
      const RoundMixer::Vector mixed = round < kMixedRounds ? mixer.next(x, g) : g;
      friction = mixed.head<2>();
      twist = lever * mixed(2);
      at = mixed.tail<3>();
    }
    applied_at = at;
    s = s0;
    k = k0;
    k.apply(s, at, Vec3(friction.x(), 0.0, friction.y()));
    s.L += twist * up;
    k.w += k.inv_inertia * (twist * up);
    normal = solve_normal(s, k, set, system, target);
    if (patch) *patch = {friction.norm(), limit, settled ? 0.0 : residual};
    if (settled || close_enough) break;
  }
  return set.count;
}

}  // namespace tumble::floor_detail
