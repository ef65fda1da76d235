#include "floor_contact.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "floor_geometry.hpp"
#include "floor_impulse.hpp"
#include "floor_time_of_impact.hpp"
#include "integrators.hpp"
#include "pivot_turns.hpp"

namespace tumble {

// The box's vertices, impulses and time of impact against the floor (floor_geometry.hpp,
// floor_impulse.hpp, floor_time_of_impact.hpp) are this file's vocabulary.
using namespace floor_detail;

namespace {

constexpr int kMaxImpactsPerStep = 32;

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
/// null, is the state after the whole step's flight from s (already computed by the caller),
/// and `rotated`, when not null, the attitude after it (flight's batched turns).
FloorStepResult meet_floor(Body& body, const WorldDef& w, double dt, const BodyState* flown,
                           SpinCache* spin, const Mat3* rotated = nullptr) {
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
    // The whole step's flight takes a cube's turn from its spin cache, as in flight, and a
    // general box's from the turns flight computed together.
    const BodyState next =
        k == 0 && flown ? *flown
        : k == 0 && rotated ? advance_turned(s, c, w.gravity, remaining, *rotated)
        : k == 0            ? advance(w.integrator, s, c, w.gravity, remaining, spin)
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

// Most steps of most bodies are in flight, clear of the floor: that case is one call of the
// integrator and two comparisons, kept apart from the contact code (whose stack frame and
// saved registers were a third of the instructions of a cube's flight). `fly` gives the whole
// step's flight from the body's state; `rotated` is what meet_floor takes for its own.
template <class Fly>
FloorStepResult step_with_floor(Body& body, const WorldDef& w, double dt, SpinCache* spin,
                                const Mat3* rotated, const Fly& fly) {
  BodyState& s = body.s;
  const BodyConstants& c = body.c;
  if (!w.floor) {
    s = fly(s);
    return {};
  }
  const double floor_y = w.floor->height;
  if (!clear_of_floor(s, c, floor_y)) return meet_floor(body, w, dt, nullptr, spin, rotated);
  const BodyState next = fly(s);
  if (!clear_of_floor(next, c, floor_y)) return meet_floor(body, w, dt, &next, spin);
  s = next;
  return {};
}

}  // namespace

FloorStepResult advance_with_floor(Body& body, const WorldDef& w, double dt, SpinCache* spin) {
  return step_with_floor(body, w, dt, spin, nullptr, [&](const BodyState& s) {
    return advance(w.integrator, s, body.c, w.gravity, dt, spin);
  });
}

FloorStepResult advance_with_floor(Body& body, const WorldDef& w, double dt, SpinCache* spin,
                                   const Mat3& rotated) {
  return step_with_floor(body, w, dt, spin, &rotated, [&](const BodyState& s) {
    return advance_turned(s, body.c, w.gravity, dt, rotated);
  });
}

}  // namespace tumble
