#include "floor_impulse.hpp"

#include <Eigen/Cholesky>

#include "friction_rounds.hpp"

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
// decelerates at exactly μ g. The rounds are mixed (RoundMixer, friction_rounds.hpp), with
// guards for a map with kinks:
// - after kMixedRounds the rounds go on plain, for an exchange still far from its fixed point
//   (mixing can circle a kink where plain rounds creep in);
// - a mixed input that lifts the body off the floor (no load: friction's torque, extrapolated
//   past the last cone, turns every vertex up) is dropped for the closest round's output, and
//   the rounds go on plain. Before, the exchange ended there, with that friction applied and
//   no normal impulse to bound it: 3 of the 2,936 sliding edges of the friction tests. Should
//   a plain round lift it too (none has, in 30,000 such edges and a 10,000-cube landing), the
//   exchange ends without friction;
// - an exchange the rounds leave more than kPolishFrom of its limit off takes a few Newton
//   steps (polish), and if it is still that far off (Newton stalls where its differences
//   straddle a kink), kCreepRounds more plain rounds from the closest round, and Newton again;
// - the last round applies the output of the round that came closest to its fixed point, so
//   what is left in the patch is always inside its cone.
// The answer is still the rounds' own fixed point.
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
  const FrictionRounds rounds(s0, k0, set, system, target, mu);
  const double lever = c.bounding_radius;  // m: the twist's scale among the unknowns
  RoundMixer mixer;
  constexpr int kRounds = 32;       // at most; most exchanges settle within 3–10
  constexpr int kMixedRounds = 16;  // then plain rounds, for an exchange still far off:
  constexpr double kFarOff = 1e-7;  // its closest residual above this part of μ Σ jₙ
  constexpr double kPolishFrom = 1e-5;  // Newton for a closest residual above this part,
  constexpr int kCreepRounds = 64;      // then as many more plain rounds if it stays so
  ClosestRound closest;  // the output applied if the rounds end unsettled
  bool plain = false;    // mixing given up (a mixed input lifted the body)
  RoundInput in;         // what the last round applied: no friction yet
  // Back to the closest round's output, with plain rounds from there.
  auto plain_from_closest = [&] {
    plain = true;
    in = closest.output;
    normal = rounds.apply(in, s, k);
  };
  for (int round = 0, last = kRounds - 1; round <= last; ++round) {
    const RoundOutput out = rounds.read(in, normal, k);
    if (out.limit <= 0.0) {  // no load
      if (round == 0) break;  // the body leaves the floor: no friction
      if (plain || closest.residual == INFINITY) {  // even the closest round's lifts it
        normal = rounds.apply(RoundInput{}, s, k);  // no friction rather than no load
        if (patch) *patch = {};
        break;
      }
      plain_from_closest();
      continue;
    }
    if (round == 0) in.at = out.next.at;  // no friction yet: where it was applied is moot
    const double moved = (out.next.friction - in.friction).norm();
    const double turned = std::abs(out.next.twist - in.twist);
    const bool settled = moved <= 1e-13 * (1.0 + out.next.friction.norm()) &&
                         turned <= 1e-13 * (1.0 + std::abs(out.next.twist));
    double residual = moved + turned / lever, limit = out.limit;
    if (!settled && residual < closest.residual) closest = {residual, out.next, out.limit};
    // Plain rounds cost a tenth of a μ = 1 landing's time when every unsettled exchange took
    // them; most of those were creeping within 1e-7 of their fixed point already.
    const bool close_enough =
        round >= kMixedRounds - 1 && closest.residual <= kFarOff * closest.limit;
    if (settled) {
      in = out.next;
    } else if (round == last || close_enough) {
      if (closest.residual > kPolishFrom * closest.limit) polish(rounds, lever, closest);
      if (round == kRounds - 1 && closest.residual > kPolishFrom * closest.limit) {
        last += kCreepRounds;  // Newton stalled on a kink: plain rounds creep in
        plain_from_closest();
        continue;
      }
      in = closest.output;
      residual = closest.residual;
      limit = closest.limit;
    } else if (round < kMixedRounds && !plain) {
      in = round_input(mixer.next(round_vector(in, lever), round_vector(out.next, lever)), lever);
    } else {
      in = out.next;
    }
    normal = rounds.apply(in, s, k);
    if (patch) *patch = {in.friction.norm(), limit, settled ? 0.0 : residual};
    if (settled || close_enough) break;
  }
  return set.count;
}

}  // namespace tumble::floor_detail
