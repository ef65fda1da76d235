#include "floor_contact.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include <Eigen/Cholesky>
#include <boost/math/tools/toms748_solve.hpp>

#include "active_set.hpp"
#include "hermite_root.hpp"
#include "integrators.hpp"
#include "pivot_turns.hpp"

namespace tumble {
namespace {

constexpr int kMaxImpactsPerStep = 32;
constexpr double kSlop = 1e-12;          // m: deeper than this below the floor is penetration.
constexpr double kSimultaneous = 1e-9;   // m: vertices this close to the lowest hit together.
constexpr double kContactBand = 1e-6;    // m: vertices this close to the floor are touching.
// Of the step: how far before the secant's root the closing evaluation goes (1e-15 of the step
// let round-off in the heights turn it down at times). The narrowest bracket tried around the
// guess is kGuessRoundOff (hermite_root.hpp): a body that does not turn, whose guess is exact
// but for round-off.
constexpr double kClosingOffset = 1e-14;
constexpr int kMaxPoints = kMaxActiveSetPoints;  // a box has 8 vertices


/// Body-frame offsets and world velocities of the vertices touching the floor.
struct ContactSet {
  int count = 0;
  std::array<Vec3, kMaxPoints> r;  // world offset from the centre of mass, m
};

/// The box's half edges in the world: R's columns times the half extents. Vertex i is the
/// centre plus ±a ± b ± c (the signs of body_vertex): three products for all eight vertices
/// instead of eight 3×3 products, to the same bits (R (±h) sums the same three products).
struct HalfEdges {
  Vec3 a, b, c;
  HalfEdges(const BodyState& s, const BodyConstants& k)
      : a(s.R.col(0) * k.half_extents.x()),
        b(s.R.col(1) * k.half_extents.y()),
        c(s.R.col(2) * k.half_extents.z()) {}
  /// Offset of vertex i from the centre of mass, world, m.
  Vec3 vertex(int i) const {
    return ((i & 1) ? a : Vec3(-a)) + ((i & 2) ? b : Vec3(-b)) + ((i & 4) ? c : Vec3(-c));
  }
  /// Its height alone.
  double vertex_y(int i) const {
    return ((i & 1) ? a.y() : -a.y()) + ((i & 2) ? b.y() : -b.y()) + ((i & 4) ? c.y() : -c.y());
  }
};

/// Height of the lowest of the vertices in `mask` (bit i: vertex i), m; +∞ for an empty mask.
double lowest_masked_y(const BodyState& s, const BodyConstants& c, unsigned mask) {
  const HalfEdges e(s, c);
  double lowest = INFINITY;
  for (int i = 0; i < 8; ++i)
    if (mask & (1u << i)) lowest = std::min(lowest, s.x.y() + e.vertex_y(i));
  return lowest;
}

/// The body's bounding sphere lies wholly above the floor plane y = floor_y.
bool clear_of_floor(const BodyState& s, const BodyConstants& c, double floor_y) {
  return s.x.y() - c.bounding_radius > floor_y;
}

ContactSet touching_vertices(const BodyState& s, const BodyConstants& c, double limit_y) {
  ContactSet set;
  const HalfEdges e(s, c);
  for (int i = 0; i < 8; ++i)
    if (s.x.y() + e.vertex_y(i) <= limit_y) set.r[set.count++] = e.vertex(i);
  return set;
}

/// The patch friction impulse of one exchange and its Coulomb limit μ Σ jₙ, N·s.
struct PatchFriction {
  double impulse = 0.0;
  double limit = 0.0;
};

/// Kinematic state of the body during an impulse exchange (I⁻¹ is fixed over an impulse).
struct Kinematics {
  Vec3 v;
  Vec3 w;
  Mat3 inv_inertia;
  double inv_mass;
  Vec3 point_velocity(const Vec3& r) const { return v + w.cross(r); }
  void apply(BodyState& s, const Vec3& r, const Vec3& j) {
    s.P += j;
    s.L += r.cross(j);
    v += inv_mass * j;
    w += inv_inertia * r.cross(j);
  }
};

using Impulses = std::array<double, kMaxPoints>;

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

Kinematics kinematics_of(const BodyState& s, const BodyConstants& c) {
  Kinematics k;
  k.inv_mass = c.inv_mass;
  k.inv_inertia = inverse_inertia_world(s, c);
  k.v = s.P * c.inv_mass;
  k.w = k.inv_inertia * s.L;
  return k;
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

/// The last rounds' friction and twist impulses, for extrapolation.
struct RoundHistory {
  int count = 0;
  std::array<Eigen::Vector2d, 2> friction;
  std::array<double, 2> twist{};
};

// The rounds below converge linearly: for a box sticking on an edge each round removes about
// 60 % of the error, so 16 rounds ended near 1e-7 relative, never at 1e-13. Aitken's Δ²
// process (Aitken 1926) turns three iterates x₀, x₁, x₂ of such a sequence into its limit
// x₂ + ρ/(1 − ρ) (x₂ − x₁), ρ the ratio of successive changes: the friction impulse and the
// twist each get it once they have three iterates whose change shrinks steadily (0 < ρ < 0.9),
// then start afresh; the result is put back inside the friction cone, and the rounds go on
// from there, so the answer is still the rounds' own fixed point.
void extrapolate(RoundHistory& h, Eigen::Vector2d& friction, double& twist, double limit,
                 double twist_limit) {
  if (h.count < 2) {
    h.friction[h.count] = friction;
    h.twist[h.count] = twist;
    ++h.count;
    return;
  }
  const Eigen::Vector2d d1 = h.friction[1] - h.friction[0], d2 = friction - h.friction[1];
  const double rho = d1.squaredNorm() > 0.0 ? d2.dot(d1) / d1.squaredNorm() : 0.0;
  if (rho > 0.0 && rho < 0.9) {
    friction += rho / (1.0 - rho) * d2;
    if (friction.norm() > limit) friction *= limit / friction.norm();
  }
  const double t1 = h.twist[1] - h.twist[0], t2 = twist - h.twist[1];
  const double tau = t1 != 0.0 ? t2 / t1 : 0.0;
  if (tau > 0.0 && tau < 0.9)
    twist = std::clamp(twist + tau / (1.0 - tau) * t2, -twist_limit, twist_limit);
  h.count = 0;
}

// Coulomb friction on the contact patch as a whole, alternated with the exact normal solve
// to a fixed point: the tangential impulse F acts at the normal-impulse-weighted centroid of
// the contacts, cancels the sliding velocity there through its 2×2 tangential mass, and is
// clamped to the cone |F| ≤ μ Σ jₙ (Stewart & Trinkle 1996 reduce to this for one patch).
// Each round re-solves the normal impulses from the state before the impulse exchange, so the
// load shifts to the leading edge of a sliding box instead of tipping it, and a flat slide
// decelerates at exactly μ g.
int resolve(BodyState& s, const BodyConstants& c, const ContactSet& set, const Impulses& target,
            double mu, PatchFriction* patch = nullptr) {
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
  RoundHistory history;
  for (int round = 0; round < 16; ++round) {
    double total = 0.0;
    Vec3 centroid = Vec3::Zero();
    for (int i = 0; i < set.count; ++i) total += normal[i], centroid += normal[i] * set.r[i];
    if (total <= 0.0) break;
    centroid /= total;
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
    const bool settled = (next - friction).norm() <= 1e-13 * (1.0 + next.norm()) &&
                         std::abs(next_twist - twist) <= 1e-13 * (1.0 + std::abs(next_twist));
    friction = next;
    twist = next_twist;
    if (!settled) extrapolate(history, friction, twist, mu * total, mu * total * radius);
    s = s0;
    k = k0;
    k.apply(s, centroid, Vec3(friction.x(), 0.0, friction.y()));
    s.L += twist * up;
    k.w += k.inv_inertia * (twist * up);
    normal = solve_normal(s, k, set, system, target);
    if (patch) *patch = {friction.norm(), mu * total};
    if (settled) break;
  }
  return set.count;
}

// A vertex touches within kContactBand of the floor; one a little higher, within v_rest dt (the
// distance a vertex at the rest speed covers in a step: 0.5 g dt², 85 µm at dt = 1/240), and
// moving no faster than the rest speed either way, is in resting contact too. Without that
// band a box pivoting on an edge with friction lifts its pivot a few tens of micrometres after
// each inelastic impact and meets the floor again a step later: one impact (with its
// time-of-impact search) per step, 115 per box in a 2 s landing at μ = 1, e = 0. A vertex that
// approaches faster keeps its impact (bounces are untouched), and for e = 1 the rest speed is
// 1e-6 m/s, so the band is kContactBand.
bool in_resting_contact(const BodyState& s, const BodyConstants& c, double floor_y,
                        double rest_speed_ms, double dt) {
  const double band = std::max(kContactBand, rest_speed_ms * dt);
  if (lowest_vertex_y(s, c) > floor_y + band) return false;
  const Kinematics k = kinematics_of(s, c);
  const ContactSet set = touching_vertices(s, c, floor_y + band);
  for (int i = 0; i < set.count; ++i) {
    const double vn = k.point_velocity(set.r[i]).y();
    const bool touching = s.x.y() + set.r[i].y() <= floor_y + kContactBand;
    if (vn <= rest_speed_ms && (touching || vn >= -rest_speed_ms)) return true;
  }
  return false;
}

// Horizontal travel of a body in resting contact over a step of h seconds. Kinetic friction
// acts at its Coulomb limit μ Σ jₙ: a constant force while the patch slides. The patch took
// the friction impulse F ≤ μ Σ jₙ, so it slid for t_s = h F / (μ Σ jₙ), its centre moving along
// a parabola from v₀ to v₁, and moved with v₁ for the rest of the step:
// t_s (v₀ + v₁)/2 + (h − t_s) v₁. A slide through the whole step is the exact parabola; the
// step in which a flat slide stops travels v₀ t_s / 2; a sticking patch (F = 0) moves with its
// end-of-step velocity as the rest of the step does. So a flat slide stops at v₀²/(2 μ g) to
// round-off at any dt, where moving with the end-of-step velocity stopped v₀ dt/2 short.
// Without friction (or without a pressed point) the only horizontal force is gravity's
// horizontal part, constant: the parabola again, h (v₀ + v₁)/2, written h v₁ − h (v₁ − v₀)/2
// so that it is h v₁ to the bit when gravity is vertical (under gravity tilted 45° h v₁ slid
// a box on a frictionless floor 0.115 m too far in 2 s at dt 1/60).
Vec3 horizontal_travel(const Vec3& v0, const Vec3& v1, const PatchFriction& patch, double h) {
  const Vec3 flat(1.0, 0.0, 1.0);
  const Vec3 v0t = v0.cwiseProduct(flat), v1t = v1.cwiseProduct(flat);
  if (patch.limit <= 0.0) return h * v1t - (0.5 * h) * (v1t - v0t);
  const double slid = h * std::min(1.0, patch.impulse / patch.limit);
  return 0.5 * slid * (v0t + v1t) + (h - slid) * v1t;
}

/// The vertices in resting contact over the next h seconds and their normal targets: those
/// touching (within kContactBand; target 0) and those that would reach the floor within h at
/// the current velocities (target −gap / h: they may approach by their gap).
ContactSet resting_set(const BodyState& s, const BodyConstants& c, double floor_y, double h,
                       Impulses& target) {
  const Kinematics k = kinematics_of(s, c);
  ContactSet set;
  target = {};
  const HalfEdges e(s, c);
  for (int i = 0; i < 8; ++i) {
    const Vec3 r = e.vertex(i);
    const double gap = s.x.y() + r.y() - floor_y;
    const double vn = k.point_velocity(r).y();
    if (gap > kContactBand && gap + h * vn >= 0.0) continue;
    target[set.count] = gap <= kContactBand ? 0.0 : -gap / h;
    set.r[set.count++] = r;
  }
  return set;
}

/// What round-off or the rotation's curvature left below the floor, projected back, and its
/// approach removed.
void lift_out_of_floor(BodyState& s, const BodyConstants& c, double floor_y) {
  const double lowest = lowest_vertex_y(s, c);
  if (lowest < floor_y) {
    s.x.y() += floor_y - lowest;
    const ContactSet set = touching_vertices(s, c, floor_y + kSimultaneous);
    resolve(s, c, set, Impulses{}, c.friction);
  }
}

/// True when both points r0 and r1 (world offsets from the centre) of a body moving at v, ω
/// are still to within `still` m/s.
bool both_still(const Vec3& v, const Vec3& w, const Vec3& r0, const Vec3& r1, double still) {
  return (v + w.cross(r0)).norm() <= still && (v + w.cross(r1)).norm() <= still;
}

// A pivot's vertices count as still below this speed (m/s; plus this fraction of the rim's
// speed |ω| r): the solve leaves a sticking vertex ~1e-16 m/s, the projection out of the floor
// after a step up to ~1e-9. Over a step of 1/60 s, 1e-7 m/s is 2 nm.
constexpr double kPivotStill = 1e-7;

// How fast a pivot may move at the start of a step that follows a first-order one (m/s):
// that step held the pivot at its start pose and then turned the body through h ω, which
// leaves the pivot moving at up to |ω|² h r. Without this allowance a box that reached its
// pivot through an impact or a landing stayed on the first-order step for good, each step
// leaving the next the same residue.
double settling(const Vec3& w, const BodyConstants& c, double h) {
  return h * w.squaredNorm() * c.bounding_radius;
}

/// True when the pivot r0, r1 (from the centre, world, m; r0 = r1 for a corner) of `solved`,
/// the state after the contact solve, is still at the end (kPivotStill) and was at the start
/// (v_start, L_start: before the solve; within `settling` too). Sets the angular velocities
/// before and after the solve (rad/s); the solve has not turned R, so one I⁻¹ serves both.
bool pivot_held(const BodyState& solved, const BodyConstants& c, double h, const Vec3& v_start,
                const Vec3& L_start, const Vec3& r0, const Vec3& r1, Vec3& w_start,
                Vec3& w_end) {
  const Mat3 inv_inertia = inverse_inertia_world(solved, c);
  w_start = inv_inertia * L_start;
  w_end = inv_inertia * solved.L;
  const double still = kPivotStill * (1.0 + c.bounding_radius * w_start.norm());
  return both_still(v_start, w_start, r0, r1, still + settling(w_start, c, h)) &&
         both_still(c.inv_mass * solved.P, w_end, r0, r1, still);
}

// A body resting on one corner or one edge that sticks, and that was pivoting about it
// already, turns about it exactly (corner_step, edge_step: second order) instead of moving
// with its end-of-step velocities. The solve before decided that the pivot holds: exactly its
// corner or edge touches and none is about to (all targets 0), the patch sticks, and its
// vertices are still at the end and were at the start (within `settling`). Returns false,
// touching nothing, otherwise.
bool turn_about_pivot(BodyState& s, const BodyConstants& c, const Vec3& gravity, double h,
                      const ContactSet& set, const Impulses& target, const PatchFriction& patch,
                      const Vec3& v_start, const Vec3& L_start) {
  if (set.count > 2 || !(patch.impulse < patch.limit)) return false;
  for (int i = 0; i < set.count; ++i)
    if (target[i] != 0.0) return false;
  const Vec3& r0 = set.r[0];
  const Vec3& r1 = set.r[set.count - 1];
  Vec3 w_start, w_end;
  if (!pivot_held(s, c, h, v_start, L_start, r0, r1, w_start, w_end)) return false;
  if (set.count == 1)
    corner_step(s, c, gravity, h, c.mass * v_start, L_start, r0);
  else
    edge_step(s, c, gravity, h, w_start, w_end, r0, r1);
  return true;
}

void contact_step(BodyState& s, const BodyConstants& c, const Vec3& gravity, double floor_y,
                  double h, double rest_speed_ms, bool may_land = true);

/// True when exactly two vertices of `set` touch (target 0) and the others are about to
/// (targets below 0): a box on an edge whose face may land within the step.
bool lands_from_edge(const ContactSet& set, const Impulses& target) {
  int touching = 0;
  for (int i = 0; i < set.count; ++i) touching += target[i] == 0.0 ? 1 : 0;
  return touching == 2 && set.count > 2;
}

/// The turn φ > 0 about `axis` (through the pivot, world; turning the body's way) at which a
/// point q from the pivot meets the floor, `height` below the pivot (m): the first root of
/// q_y(φ) = −height by Rodrigues' formula, or +∞ when it does not meet it within a half turn.
double landing_turn(const Vec3& axis, const Vec3& q, double height) {
  // q_y(φ) = A cos φ + B sin φ + C, the part along the axis not turning.
  const double along = axis.dot(q) * axis.y();
  const double A = q.y() - along, B = axis.cross(q).y(), C = along + height;
  const double R = std::hypot(A, B);
  if (R == 0.0 || std::abs(C) > R) return INFINITY;
  const double base = std::atan2(B, A), spread = std::acos(-C / R);
  double best = INFINITY;
  for (double phi : {base - spread, base + spread}) {
    phi = std::remainder(phi, 2.0 * std::numbers::pi);
    if (phi < 0.0) phi += 2.0 * std::numbers::pi;
    if (phi > 0.0 && phi < best) best = phi;
  }
  return best;
}

// A box rocking on an edge lands on a face (or on another edge) within the step: the resting
// step took that landing as a speculative contact, the face's vertices allowed to approach by
// their gap, which left the rock after it ~5 % slower than Housner's rigid, inelastic landing
// (Housner, Bull. Seismol. Soc. Am. 53, 1963: the angular momentum about the landing edge is
// kept, a quarter of the rate for a cube). Here the landing is found at its time: the edge's
// pendulum (edge_step's model, θ(t) = ω₀ t + α t² / 2 with α from the solve holding the edge)
// turns to the landing angle, the landing is an impact with the floor's restitution, and the
// resting step takes the rest of the step. Returns false, touching nothing, unless the edge
// sticks and was and stays still, as in turn_about_pivot. With no landing within the step the
// edge turns the whole step.
bool land_from_edge(BodyState& s, const BodyConstants& c, const Vec3& gravity, double floor_y,
                    double h, double rest_speed_ms, const ContactSet& set,
                    const Impulses& target) {
  ContactSet edge;
  for (int i = 0; i < set.count; ++i)
    if (target[i] == 0.0) edge.r[edge.count++] = set.r[i];
  BodyState t = s;
  t.P += (h * c.mass) * gravity;
  PatchFriction patch;
  resolve(t, c, edge, Impulses{}, c.friction, &patch);
  if (!(patch.impulse < patch.limit)) return false;
  const Vec3 &r0 = edge.r[0], &r1 = edge.r[1];
  Vec3 w_start, w_end;
  if (!pivot_held(t, c, h, c.inv_mass * s.P, s.L, r0, r1, w_start, w_end)) return false;
  Vec3 axis = (r1 - r0).normalized();
  double w0 = axis.dot(w_start), alpha = (axis.dot(w_end) - w0) / h;
  const double turn = w0 * h + 0.5 * alpha * h * h;  // the step's turn without a landing
  if (turn == 0.0) return false;
  if (turn < 0.0) axis = -axis, w0 = -w0, alpha = -alpha;  // turning the positive way
  double landing = INFINITY;
  const double height = s.x.y() + r0.y() - floor_y;
  for (int i = 0; i < set.count; ++i)
    if (target[i] < 0.0) landing = std::min(landing, landing_turn(axis, set.r[i] - r0, height));
  if (!(landing < std::abs(turn))) {  // no landing within the step: the edge's turn
    edge_step(t, c, gravity, h, w_start, w_end, r0, r1);
    lift_out_of_floor(t, c, floor_y);
    s = t;
    return true;
  }
  // ω₀ t + α t² / 2 = landing, its first root in (0, h], written without cancellation.
  const double disc = w0 * w0 + 2.0 * alpha * landing;
  if (!(disc >= 0.0)) return false;
  const double when = 2.0 * landing / (w0 + std::sqrt(disc));
  if (!(when > 0.0 && when <= h)) return false;
  edge_step(s, c, gravity, when, w0 * axis, (w0 + alpha * when) * axis, r0, r1);
  resolve_floor_impact(s, c, floor_y, c.restitution, c.friction, rest_speed_ms);
  if (h - when > 1e-15)  // the rest of the step, without a second landing in it
    contact_step(s, c, gravity, floor_y, h - when, rest_speed_ms, false);
  return true;
}

// Resting contact over h seconds, a velocity-level step in the spirit of Guendelman, Bridson
// & Fedkiw 2003 (§5–6): gravity first, then inelastic contact impulses (with friction), then
// positions with the corrected velocities. Touching vertices may not approach; a vertex that
// would reach the floor within the step may approach only by its gap (a speculative contact,
// as in Box2D and Jolt), so a rocking box lands flat at the end of the step instead of
// rotating through the floor and being pushed out. A flat box ends with v = 0 and x
// unchanged: no sinking, no jitter. A box pivoting on a sticking corner or edge turns about it
// exactly instead (turn_about_pivot), and one rocking on an edge lands at its time
// (land_from_edge; may_land false: not in this step). rest_speed_ms: the floor's rest speed
// (rest_speed), for those landings.
void contact_step(BodyState& s, const BodyConstants& c, const Vec3& gravity, double floor_y,
                  double h, double rest_speed_ms, bool may_land) {
  const Vec3 v_start = c.inv_mass * s.P;
  const Vec3 L_start = s.L;
  const Vec3 P_start = s.P;
  s.P += (h * c.mass) * gravity;
  PatchFriction patch;
  Impulses target;
  const ContactSet set = resting_set(s, c, floor_y, h, target);
  if (may_land && c.friction > 0.0 && lands_from_edge(set, target)) {
    BodyState start = s;
    start.P = P_start;
    if (land_from_edge(start, c, gravity, floor_y, h, rest_speed_ms, set, target)) {
      s = start;
      return;
    }
  }
  resolve(s, c, set, target, c.friction, &patch);
  if (turn_about_pivot(s, c, gravity, h, set, target, patch, v_start, L_start)) {
    lift_out_of_floor(s, c, floor_y);
    return;
  }
  s.x += horizontal_travel(v_start, c.inv_mass * s.P, patch, h);
  s.x.y() += h * c.inv_mass * s.P.y();
  if (!s.L.isZero()) {
    s.R = rotation_from_vector(h * angular_velocity(s, c)) * s.R;
    orthonormalize(s.R);
  }
  lift_out_of_floor(s, c, floor_y);
}

/// Vertical speed of vertex i (offset r from the centre, world) of a body moving at v, ω:
/// (v + ω × r)_y, m/s.
double vertex_speed_y(const Vec3& v, const Vec3& w, const Vec3& r) {
  return v.y() + w.z() * r.x() - w.x() * r.z();
}

/// Vertical speed (m/s) below which a face vertex counts as still: over a step of 1/60 s it
/// moves 1.7e-14 m, round-off of the positions themselves.
constexpr double kStillSpeed = 1e-12;

/// Whether the body lies still on one face of a frictionless floor over the next h seconds:
/// that face's four vertices touch (within kContactBand) without a vertical velocity, and the
/// other four are above the band and stay above the floor. The floor's impulse then only
/// cancels gravity's vertical impulse, at the four corners of the face around the centre of
/// mass: no torque and no friction, so the body glides and spins freely (v_y = 0, L and the
/// horizontal momentum as in flight), and contact_step needs no impulse solve. This is what
/// the solve would find (to round-off): four still vertices fix v_y and the two horizontal
/// components of ω. A separated fall onto a frictionless floor ends with most boxes so,
/// spinning about the vertical (1,169 of 2,000 cubes after 2 s).
bool glides_on_face(const BodyState& s, const BodyConstants& c, const Vec3& gravity,
                    double floor_y, double h) {
  if (c.friction != 0.0 || gravity.y() > 0.0) return false;
  if (std::abs(c.inv_mass * s.P.y()) > 1e-9) return false;  // not still: no need to look
  const Vec3 v = c.inv_mass * s.P;
  const Vec3 w = angular_velocity(s, c);
  // A vertex above the band sinks at most this fast (m/s) over the step.
  const double sink = std::max(-(v.y() + h * gravity.y()), 0.0) + w.norm() * c.bounding_radius;
  const HalfEdges e(s, c);
  unsigned touching = 0;
  for (int i = 0; i < 8; ++i) {
    const double gap = s.x.y() + e.vertex_y(i) - floor_y;
    if (gap > kContactBand && gap - h * sink >= 0.0) continue;  // stays above the floor
    const Vec3 r = e.vertex(i);
    const double vn = vertex_speed_y(v, w, r);
    if (gap <= kContactBand) {
      if (std::abs(vn) > kStillSpeed) return false;
      touching |= 1u << i;
    } else if (gap + h * std::min(vn + h * gravity.y(), 0.0) < 0.0) {
      return false;  // a vertex above reaches the floor within the step
    }
  }
  // The four vertices of one face share one sign of ±a, ±b or ±c (HalfEdges' numbering).
  for (unsigned face : {0x55u, 0xAAu, 0x33u, 0xCCu, 0x0Fu, 0xF0u})
    if (touching == face) return true;
  return false;
}

/// contact_step for a body that glides_on_face: its flight with the vertical momentum held at
/// zero (the turn from `spin` when it holds it, as in flight). Round-off in the turn that
/// leaves a vertex below the floor is projected back.
void glide_step(BodyState& s, const BodyConstants& c, const Vec3& gravity, double floor_y,
                double h, SpinCache* spin) {
  s.P += (h * c.mass) * gravity;
  s.P.y() = 0.0;  // the floor's impulse cancels gravity's
  // Gravity's horizontal part is the only horizontal force: the centre's parabola,
  // h v₁ − ½ h² g_h (h v₁ to the bit when gravity is vertical).
  s.x += h * c.inv_mass * s.P;
  s.x -= (0.5 * h * h) * Vec3(gravity.x(), 0.0, gravity.z());
  if (!s.L.isZero()) {
    // A cube's ω = L / I, as in flight: the same bits step after step, so `spin` holds its turn.
    const Vec3 angle = c.shape == InertiaShape::isotropic ? Vec3((h * c.inv_inertia.x()) * s.L)
                                                          : Vec3(h * angular_velocity(s, c));
    s.R = (spin ? cached_turn(angle, *spin) : rotation_from_vector(angle)) * s.R;
  }
  const double lowest = lowest_vertex_y(s, c);
  if (lowest < floor_y) s.x.y() += floor_y - lowest;
}

/// Fourth time derivative of the height of a point at offset r (world) on a body turning at ω
/// about a fixed axis: |ω|⁴ times r's component normal to ω, its y (m/s⁴).
double turn_fourth_derivative_y(const Vec3& w, const Vec3& r) {
  const double w2 = w.squaredNorm();
  return w2 * (w2 * r.y() - r.dot(w) * w.y());
}

/// A first guess at the time of impact and how far it may be off.
struct ImpactGuess {
  double time = 0.0;   ///< s, in (0, h]; h when no vertex ends below the floor.
  double error = 0.0;  ///< Bound on |time − the impact's time|, s.
};

/// The guess of time_of_impact: the earliest root among the vertices of `mask` that end below
/// the floor, each from the cubic Hermite interpolant of its height and vertical speed at both
/// ends of the step (states s and end), plus its leading error term. The error bound is the
/// cubic's alone, generous for the quartic: a cubic Hermite interpolant over h is off by at
/// most h⁴/384 max|y⁗|; the centre's height is a parabola (y⁗ = 0) and a vertex's turn about
/// it has |y⁗| ≤ 16 Ω⁴ r, where Ω² = 2E / I_min bounds |ω|² in torque-free motion (E the
/// rotational energy; 16 a generous constant for the derivatives of ω a general body adds),
/// divided by the speed at the root; never below kGuessRoundOff h, near the evaluations' own
/// round-off. The bound only sets the bracket tried first, which evaluations then check.
ImpactGuess hermite_time_of_impact(const BodyState& s, const BodyState& end,
                                   const BodyConstants& c, double floor_y, double h,
                                   unsigned mask) {
  const HalfEdges e0(s, c), e1(end, c);
  const Vec3 v0 = c.inv_mass * s.P, v1 = c.inv_mass * end.P;
  const Vec3 w0 = angular_velocity(s, c), w1 = angular_velocity(end, c);
  const double h2 = h * h;
  double earliest = 1.0, speed = 0.0;
  for (int i = 0; i < 8; ++i) {
    if (!(mask & (1u << i))) continue;
    const double y1 = end.x.y() + e1.vertex_y(i) - floor_y;
    const double y0 = s.x.y() + e0.vertex_y(i) - floor_y;
    if (y1 >= 0.0 || y0 <= 0.0) continue;
    const Vec3 r0 = e0.vertex(i), r1 = e1.vertex(i);
    const double d0 = h * vertex_speed_y(v0, w0, r0);
    const double d1 = h * vertex_speed_y(v1, w1, r1);
    // The cubic's error y⁗ h⁴ τ²(τ − 1)² / 24 with the turn's y⁗ (the mean of both ends):
    // without it one spinning cube's guess in five came late by more than the tolerance (the
    // lowest vertex's y⁗ is negative: the true height lies below the cubic).
    const double y4 =
        0.5 * (turn_fourth_derivative_y(w0, r0) + turn_fourth_derivative_y(w1, r1));
    const HermiteRoot root = hermite_root(y0, d0, y1, d1, y4 * h2 * h2 / 24.0);
    if (root.tau < earliest) earliest = root.tau, speed = std::abs(root.slope) / h;
  }
  if (speed == 0.0) return {h, INFINITY};  // no vertex of the mask ends below the floor
  const double omega2 = w0.dot(s.L) * c.inv_inertia.maxCoeff();  // 2E / I_min ≥ |ω|²
  const double y4_bound = 16.0 * omega2 * omega2 * c.bounding_radius;
  const double h4 = h * h * h * h;
  const double error = h4 / 384.0 * y4_bound / speed;
  return {earliest * h, std::max(error, kGuessRoundOff * h)};
}

/// Earliest time in [0, h] at which a vertex of `mask` reaches the floor (it is above at 0
/// and some vertex of the mask is below at h, in the state `end`). Returns the non-penetrating
/// end of the final bracket, so a body is never left inside the floor, and sets `at` to the
/// body's state then.
///
/// Both searches end on a time they evaluated with the body above the floor (the lower end of
/// the bracket), so that evaluation's state is kept rather than computed again: the latest
/// time evaluated above the floor is that end. One trajectory evaluation saved per impact,
/// the same bits.
double time_of_impact(const BodyState& s, const BodyState& end, const BodyConstants& c,
                      const WorldDef& w, double floor_y, double h, unsigned mask,
                      double height_at_h, int& evaluations, BodyState& at) {
  double at_t = 0.0;
  at = s;
  auto height_of = [&](const BodyState& st) {
    return (mask == 0xFF ? lowest_vertex_y(st, c) : lowest_masked_y(st, c, mask)) - floor_y;
  };
  auto height = [&](double t) {
    ++evaluations;
    const BodyState st = advance(w.integrator, s, c, w.gravity, t);
    const double y = height_of(st);
    if (y >= 0.0 && t > at_t) at_t = t, at = st;
    return y;
  };
  auto state_at = [&](double t) {
    if (t != at_t) at = advance(w.integrator, s, c, w.gravity, t);  // not met: kept for safety
    return t;
  };
  if (w.toi == ToiMethod::bisection) {
    // The seed's search: halve the interval, keeping the last time that does not penetrate.
    double lo = 0.0, hi = h;
    while (hi - lo > w.toi_tolerance) {
      const double mid = 0.5 * (lo + hi);
      (height(mid) < 0.0 ? hi : lo) = mid;
    }
    return state_at(lo);
  }
  const double tol = w.toi_tolerance;
  // Why a guess first: both ends of the step are known states, and each vertex's height and
  // vertical speed there fix its cubic Hermite interpolant (hermite_time_of_impact). Two
  // evaluations, at its root ± its error bound (at most tol/2), then bracket the impact;
  // TOMS 748 took 4.1–4.4 an impact in the landings of cubes and general boxes. When they do
  // not (the lowest vertex changes within the step, a tolerance below the guess's error), the
  // one that failed narrows the bracket TOMS 748 starts from.
  double lo = 0.0, hi = h, y_lo = height_of(s), y_hi = height_at_h;
  const ImpactGuess guess = hermite_time_of_impact(s, end, c, floor_y, h, mask);
  const double offset = kClosingOffset * h;
  const double half_width = std::min(guess.error, 0.45 * tol);
  const double a = guess.time - half_width, b = guess.time + half_width;
  if (a > 0.0 && b < h) {
    const double ya = height(a);
    if (ya < 0.0) {
      hi = a, y_hi = ya;
    } else {
      const double yb = height(b);
      if (yb < 0.0) {
        // A bracket wider than round-off (a spinning body's, up to the tolerance) is closed by
        // its secant, exact to ~(b − a)² y''/y' ≈ 1e-18 s, and one evaluation just before it:
        // the time comes out to round-off. The seed scene ends 1.2e-11 m from its reference
        // so, 2e-7 m with TOMS 748 alone (its last bracket anywhere inside the tolerance) and
        // 1e-6 m with the guess's bracket unclosed.
        const double closer = a + (b - a) * (ya / (ya - yb)) - offset;
        if (half_width > offset && closer > a && height(closer) >= 0.0)
          return state_at(closer);
        return state_at(a);
      }
      lo = b, y_lo = yb;
    }
  }
  // TOMS 748 (Alefeld, Potra & Shi 1995) on the lowest-vertex height along the trajectory:
  // cubic inverse interpolation with bracketing, a few evaluations where bisection takes
  // log2(h / tolerance). The lower end keeps the sign of height(lo) ≥ 0. The step's start is
  // s itself: its height needs no trajectory evaluation (advancing by 0 s gives s back to the
  // bit).
  std::uintmax_t max_iter = 100;
  const auto bracket = boost::math::tools::toms748_solve(
      height, lo, hi, y_lo, y_hi, [tol](double x, double y) { return y - x <= tol; }, max_iter);
  return state_at(bracket.first);
}

unsigned vertices_above(const BodyState& s, const BodyConstants& c, double y) {
  const HalfEdges e(s, c);
  unsigned mask = 0;
  for (int i = 0; i < 8; ++i)
    if (s.x.y() + e.vertex_y(i) > y) mask |= 1u << i;
  return mask;
}

}  // namespace

double rest_speed(double restitution, const Vec3& gravity, double dt) {
  return restitution >= 1.0 ? 1e-6 : 0.5 * gravity.norm() * dt;
}

int resolve_floor_impact(BodyState& s, const BodyConstants& c, double floor_height,
                         double restitution, double friction, double rest_speed_ms) {
  const double limit = std::max(lowest_vertex_y(s, c), floor_height) + kSimultaneous;
  const ContactSet set = touching_vertices(s, c, limit);
  const Impulses target = normal_targets(kinematics_of(s, c), set, restitution, rest_speed_ms);
  return resolve(s, c, set, target, friction);
}

namespace {

// The floor holds a still body against gravity that presses it in (or is zero) with a
// horizontal part that static friction can bear, |g_h| ≤ μ |g_y|. Under gravity pointing
// away from the floor, or tilted past the friction cone, a box placed on a face is not at
// rest: it lifts off or slides (before this test it started asleep and stayed put).
bool floor_holds(const BodyConstants& c, const Vec3& gravity) {
  if (gravity.y() > 0.0) return false;
  return std::hypot(gravity.x(), gravity.z()) <= c.friction * -gravity.y();
}

}  // namespace

bool rests_on_face(const BodyState& s, const BodyConstants& c, double floor_height,
                   const Vec3& gravity) {
  if (!s.P.isZero() || !s.L.isZero() || !floor_holds(c, gravity)) return false;
  if (lowest_vertex_y(s, c) < floor_height - kSlop) return false;
  return touching_vertices(s, c, floor_height + kSimultaneous).count >= 3;
}

bool at_rest_on_face(const BodyState& s, const BodyConstants& c, double floor_height) {
  if (!s.P.isZero() || !s.L.isZero()) return false;
  if (lowest_vertex_y(s, c) < floor_height - kContactBand) return false;
  return touching_vertices(s, c, floor_height + kContactBand).count >= 3;
}

bool touches_floor_on_edge_or_corner(const BodyState& s, const BodyConstants& c,
                                     double floor_height) {
  const int count = touching_vertices(s, c, floor_height + kContactBand).count;
  return count > 0 && count < 3;
}

namespace {

/// advance_with_floor for a body that may meet the floor within the step; `flown`, when not
/// null, is the state after the whole step's flight from s (already computed by the caller).
FloorStepResult meet_floor(Body& body, const WorldDef& w, double dt, const BodyState* flown,
                           SpinCache* spin) {
  FloorStepResult result;
  BodyState& s = body.s;
  const BodyConstants& c = body.c;
  const double floor_y = w.floor->height;
  const double vrest = rest_speed(c.restitution, w.gravity, w.dt);
  double remaining = dt;
  for (int k = 0; k < kMaxImpactsPerStep && remaining > 1e-15; ++k) {
    // Bounding sphere clear of the floor at both ends: no vertex test (the flight path's
    // lowest point is at an end while gravity points down).
    const bool start_clear = clear_of_floor(s, c, floor_y);
    // A gliding body is in resting contact too (four vertices touch, still).
    if (!start_clear && glides_on_face(s, c, w.gravity, floor_y, remaining)) {
      glide_step(s, c, w.gravity, floor_y, remaining, spin);
      result.touched = true;
      return result;
    }
    if (!start_clear && in_resting_contact(s, c, floor_y, vrest, w.dt)) {
      contact_step(s, c, w.gravity, floor_y, remaining, vrest);
      result.touched = true;
      return result;
    }
    // The whole step's flight takes a cube's turn from its spin cache, as in flight.
    const BodyState next = k == 0 && flown ? *flown
                           : k == 0        ? advance(w.integrator, s, c, w.gravity, remaining, spin)
                                           : advance(w.integrator, s, c, w.gravity, remaining);
    if (clear_of_floor(next, c, floor_y) && (start_clear || w.gravity.y() <= 0.0)) {
      s = next;
      return result;
    }
    const double end_height = lowest_vertex_y(next, c) - floor_y;
    if (end_height >= -kSlop) {
      s = next;
      return result;
    }
    const unsigned mask = vertices_above(s, c, floor_y + kSlop);
    if ((vertices_above(next, c, floor_y - kSlop) | mask) != 0xFF) {
      // A vertex that started on the floor ends inside it: resting contact, not an impact.
      break;
    }
    const double masked_end =
        mask == 0xFF ? end_height : lowest_masked_y(next, c, mask) - floor_y;
    BodyState at_impact;
    const double t = time_of_impact(s, next, c, w, floor_y, remaining, mask, masked_end,
                                    result.toi_iterations, at_impact);
    s = at_impact;
    resolve_floor_impact(s, c, floor_y, c.restitution, c.friction, vrest);
    ++result.impacts;
    result.touched = true;
    remaining -= t;
  }
  if (remaining > 1e-15) {
    contact_step(s, c, w.gravity, floor_y, remaining, vrest);
    result.touched = true;
  }
  return result;
}

}  // namespace

// Most steps of most bodies are in flight, clear of the floor: that case is one call of the
// integrator and two comparisons, kept apart from the contact code (whose stack frame and
// saved registers were a third of the instructions of a cube's flight).
FloorStepResult advance_with_floor(Body& body, const WorldDef& w, double dt, SpinCache* spin) {
  BodyState& s = body.s;
  const BodyConstants& c = body.c;
  if (!w.floor) {
    s = advance(w.integrator, s, c, w.gravity, dt, spin);
    return {};
  }
  const double floor_y = w.floor->height;
  if (!clear_of_floor(s, c, floor_y)) return meet_floor(body, w, dt, nullptr, spin);
  const BodyState next = advance(w.integrator, s, c, w.gravity, dt, spin);
  if (!clear_of_floor(next, c, floor_y)) return meet_floor(body, w, dt, &next, spin);
  s = next;
  return {};
}

}  // namespace tumble
