#include "contact_solver.hpp"

#include <algorithm>
#include <cmath>

#include "active_set.hpp"
#include "floor_contact.hpp"
#include "solver.hpp"

namespace tumble {

static_assert(kMaxContactPoints <= kMaxActiveSetPoints);

// The collision pass of Guendelman, Bridson & Fedkiw 2003 (§5), with each contact's impact
// solved exactly rather than iterated: the points of one contact that touch within the step
// and approach faster than the restitution threshold get simultaneous normal impulses that
// leave every active point with v⁺ₙ = −e v⁻ₙ (an active-set solve as in Baraff 1989, §4, with
// the pseudo-inverse for a rank-deficient face patch). With e = 1 the kinetic energy change
// Σ jᵢ (v⁻ᵢ + v⁺ᵢ)/2 is zero and the pair's momentum changes by ±Σ jᵢ n: both are conserved to
// round-off, as for an isolated impact with the floor. Frictionless: friction acts in the
// contact pass that follows.
int Solver::impact(Contact& c, std::size_t slot, const Vec3& gravity, double dt) {
  const double rest = rest_speed(c.restitution, gravity, dt);
  const double threshold = std::max(rest, 2.0 * gravity.norm() * dt);
  // Most contacts have no fast point. The rows' normal speeds (w·(r × n) for (w × r)·n) tell
  // so without reading the contact's points; they differ from the speeds below by round-off
  // only, inside may_be_fast's margin, so a contact passed over would have had no impact.
  if (!may_be_fast(slot, threshold)) return 0;
  SolverBody* a = body(c.a);
  SolverBody* b = body(c.b);
  std::array<int, kMaxContactPoints> idx{};
  PointVector vn(kMaxContactPoints), target(kMaxContactPoints);
  int n = 0;
  bool fast = false;
  for (int i = 0; i < c.count; ++i) {
    const ContactPoint& p = c.points[i];
    const double v = (point_velocity(b, p.rb) - point_velocity(a, p.ra)).dot(c.normal);
    if (p.separation + std::min(v, 0.0) * dt > 0.0) continue;  // does not touch this step
    fast = fast || v < -threshold;
    const double e = (c.restitution * -v < rest) ? 0.0 : c.restitution;
    idx[n] = i;
    vn(n) = v;
    target(n) = v < 0.0 ? -e * v : 0.0;
    ++n;
  }
  if (!fast) return 0;
  Contact sub = c;  // the touching points only
  sub.count = n;
  for (int i = 0; i < n; ++i) sub.points[i] = c.points[idx[i]];
  const NormalSystem sys = normal_system_of(sub, a, b);
  ActiveSetCache cache(sys);
  const PointVector impulse = solve_active_set(cache, vn.head(n), target.head(n));
  for (int i = 0; i < n; ++i) {
    if (impulse(i) <= 0.0) continue;
    const ContactPoint& p = c.points[idx[i]];
    apply(a, b, p.ra, p.rb, impulse(i) * c.normal);
  }
  return 1;
}

bool Solver::may_be_fast(std::size_t slot, double threshold) {
  // m/s: the two forms of a speed differ by round-off, ~1e-16 of the bodies' speeds (1e-10
  // m/s at 1e6 m/s), so a point passed over is slower than the threshold in both.
  constexpr double kMargin = 1e-9;
  const ContactRows& rows = rows_[slot];
  const ContactPointRows& points = point_rows_[slot];
  const SolverBody& a = at(rows.a);
  const SolverBody& b = at(rows.b);
  for (int i = 0; i < rows.count; ++i)
    if (normal_speed(a, b, rows.dir[0], points[i]) < kMargin - threshold) return true;
  return false;
}

void Solver::warm_start(std::size_t slot) {
  const ContactRows& rows = rows_[slot];
  SolverBody& a = at(rows.a);
  SolverBody& b = at(rows.b);
  const ContactImpulses& impulses = impulses_[slot];
  const ContactPointRows& points = point_rows_[slot];
  for (int i = 0; i < rows.count; ++i)
    push(a, b, a.inv_mass, b.inv_mass, rows.dir[0], points[i], impulses.normal[i]);
  const FrictionRows& f = rows.friction;
  const std::array<double, 3>& j = impulses.friction;
  const Vec3 linear = j[0] * rows.dir[1] + j[1] * rows.dir[2];
  if (a.inv_mass > 0.0) {
    a.v -= a.inv_mass * linear;
    a.w -= j[0] * f.inv_a[0] + j[1] * f.inv_a[1] + j[2] * f.inv_a[2];
  }
  b.v += b.inv_mass * linear;
  b.w += j[0] * f.inv_b[0] + j[1] * f.inv_b[1] + j[2] * f.inv_b[2];
}

namespace {

// Friction acts on the patch as a whole (as in Bepu's and PhysX's patch friction): two
// tangent rows at the patch's centre of pressure, bounded together by the disc μ Σλₙ, and a
// twist row about the normal bounded by μ Σλₙ r̄ (r̄ the points' mean distance from that
// centre). Three rows replace two per point: a face on a face had eight, which cost two thirds
// of each iteration. Sliding is unchanged (every point slides the same way, and the bound is
// the same μ Σλₙ); what the patch loses is the coupling of twist and slide of an uneven load,
// which per-point Coulomb friction resolved only at the points anyway. The centre of pressure
// comes from the warm-started normal impulses (the points' centroid when there are none):
// at the plain centroid, a box resting off-centre on another in a settling pile rocked and
// slid at 0.05 m/s for tens of seconds.
template <int N>
void solve_friction(const ContactRows& rows, ContactImpulses& impulses, Motion& a, Motion& b,
                    double ma, double mb) {
  const FrictionRows& f = rows.friction;
  const int count = N > 0 ? N : rows.count;
  double load = 0.0;
  for (int i = 0; i < count; ++i) load += impulses.normal[i];
  const double limit = rows.mu * load;
  std::array<double, 3>& total = impulses.friction;
  const Vec3 dv = b.v - a.v;
  const double old0 = total[0], old1 = total[1];
  double n0 = old0 - f.mass[0] * (rows.dir[1].dot(dv) + b.w.dot(f.ang_b[0]) - a.w.dot(f.ang_a[0]));
  double n1 = old1 - f.mass[1] * (rows.dir[2].dot(dv) + b.w.dot(f.ang_b[1]) - a.w.dot(f.ang_a[1]));
  const double len = std::sqrt(n0 * n0 + n1 * n1);
  if (len > limit) {
    const double scale = len > 0.0 ? limit / len : 0.0;
    n0 *= scale;
    n1 *= scale;
  }
  const double j0 = n0 - old0, j1 = n1 - old1;
  total[0] = n0;
  total[1] = n1;
  double j2 = 0.0;  // a single point resists no twist
  if (f.radius > 0.0) {
    const double old2 = total[2];
    const double twist_limit = limit * f.radius;
    // The twist's angular rows are n on both bodies (the floor's w is zero: a.w·n is +0 there,
    // as a.w·0 was when the floor's row was stored as zero).
    const Vec3& n = rows.dir[0];
    total[2] = std::clamp(old2 - f.mass[2] * (b.w.dot(n) - a.w.dot(n)),
                          -twist_limit, twist_limit);
    j2 = total[2] - old2;
  }
  const Vec3 j = j0 * rows.dir[1] + j1 * rows.dir[2];
  if (ma > 0.0) {
    a.v -= ma * j;
    a.w -= j0 * f.inv_a[0] + j1 * f.inv_a[1] + j2 * f.inv_a[2];
  }
  b.v += mb * j;
  b.w += j0 * f.inv_b[0] + j1 * f.inv_b[1] + j2 * f.inv_b[2];
}

// Block solve of the contact's normal impulses: all points at once through the
// pseudo-inverse of K (Box2D's two-point block solver, generalised with the pseudo-inverse
// for a face patch, whose four coplanar points have only three independent normal modes).
// Point-by-point Gauss–Seidel leaves such a patch rocking; the block step removes it. When
// the block answer would pull at a point, the points fall back to one clamped sweep.
//
// The block works in the patch's three coordinates (ContactRows): the points' normal speeds
// are vn = D y, the step is z = P Dᵀ(target − vn) = P Dᵀtarget − P G y, each point's impulse
// changes by dᵢ·z, and their sum moves the bodies by the wrench u = G z along the columns C.
// Per point only one dot product remains, so a four-point face costs about half the
// point-by-point form it replaced and an eight-vertex floor contact a third.
template <int N>
bool solve_normal_block(const ContactRows& rows, ContactImpulses& impulses, Motion& a, Motion& b,
                        double ma, double mb) {
  const int n = N > 0 ? N : rows.count;
  const Vec3 wr = b.w - a.w;
  const Vec3 y(rows.dir[0].dot(b.v - a.v) + b.w.dot(rows.cb0) - a.w.dot(rows.ca[0]),
               wr.dot(rows.ca[1]), wr.dot(rows.ca[2]));
  const Vec3 z = rows.Pt - rows.PG * y;
  std::array<double, kMaxContactPoints> next{};
  bool pushes = true;
  for (int i = 0; i < n; ++i) {
    next[i] = impulses.normal[i] + rows.D.row(i).dot(z);
    pushes = pushes && next[i] >= 0.0;
  }
  if (pushes) {
    for (int i = 0; i < n; ++i) impulses.normal[i] = next[i];
    const Vec3 u = rows.G * z;
    if (ma > 0.0) {
      a.v -= (ma * u(0)) * rows.dir[0];
      a.w -= u(0) * rows.inv_ca[0] + u(1) * rows.inv_ca[1] + u(2) * rows.inv_ca[2];
    }
    b.v += (mb * u(0)) * rows.dir[0];
    b.w += u(0) * rows.inv_cb[0] + u(1) * rows.inv_cb[1] + u(2) * rows.inv_cb[2];
    return true;
  }
  return false;
}

/// The sweep of one contact on velocities held in locals.
template <int N>
void solve_velocity_rows(const ContactRows& rows, const ContactPointRows& points,
                         ContactImpulses& impulses, Motion& a, Motion& b, double ma, double mb) {
  solve_friction<N>(rows, impulses, a, b, ma, mb);
  const int n = N > 0 ? N : rows.count;
  // One point: the clamped sweep below is the block step.
  if (n > 1 && solve_normal_block<N>(rows, impulses, a, b, ma, mb)) return;
  for (int i = 0; i < n; ++i) {
    const PointRows& r = points[i];
    const double vn = Solver::normal_speed(a, b, rows.dir[0], r);
    double& impulse = impulses.normal[i];
    const double next_i = std::max(0.0, impulse - r.normal_mass * (vn - r.target));
    const double delta = next_i - impulse;
    impulse = next_i;
    Solver::push(a, b, ma, mb, rows.dir[0], r, delta);
  }
}

/// The sweep of one contact of N points (0: any count) on bodies a and b.
template <int N>
void sweep_contact(const ContactRows& rows, const ContactPointRows& points,
                   ContactImpulses& impulses, SolverBody& body_a, SolverBody& body_b) {
  // The two bodies' velocities in locals for the whole contact: the compiler keeps them in
  // registers instead of storing them after every row (a third of the sweep's instructions).
  Motion a{body_a.v, body_a.w}, b{body_b.v, body_b.w};
  const double ma = body_a.inv_mass, mb = body_b.inv_mass;
  solve_velocity_rows<N>(rows, points, impulses, a, b, ma, mb);
  if (ma > 0.0) body_a.v = a.v, body_a.w = a.w;  // not the floor, which a colour's contacts share
  body_b.v = b.v;
  body_b.w = b.w;
}

}  // namespace

// Sequential impulses (Catto, "Iterative dynamics with temporal coherence", GDC 2005, and
// "Fast and simple physics using sequential impulses", GDC 2006): each point in turn gets the
// impulse that fixes its own relative velocity, the accumulated total is clamped (normal
// ≥ 0, friction inside the disc of radius μ λₙ) rather than each increment, and the totals
// start from the previous step's (warm starting), so a stack's static impulses carry over and
// only their change has to converge. Speculative points (Catto GDC 2013; Box2D, Jolt) may
// approach by their gap within the step but no more, so a falling body stops at the surface
// instead of penetrating first.
void Solver::solve_velocity(std::size_t slot) {
  const ContactRows& rows = rows_[slot];
  const ContactPointRows& points = point_rows_[slot];
  ContactImpulses& impulses = impulses_[slot];
  SolverBody& a = at(rows.a);
  SolverBody& b = at(rows.b);
  // A point count known when compiling unrolls the per-point loops and drops their bounds
  // checks (the same arithmetic in the same order, so the same bits): `pyramid`'s sweeps took
  // 10 % fewer instructions. Each count is its own function with its own locals; one set of
  // locals shared by the counts' inlined bodies went to the stack and cost 40 % more.
  switch (rows.count) {
    case 1: return sweep_contact<1>(rows, points, impulses, a, b);
    case 2: return sweep_contact<2>(rows, points, impulses, a, b);
    case 3: return sweep_contact<3>(rows, points, impulses, a, b);
    case 4: return sweep_contact<4>(rows, points, impulses, a, b);
    default: return sweep_contact<0>(rows, points, impulses, a, b);
  }
}


NormalSystem Solver::normal_system_of(const Contact& c, const SolverBody* a,
                                      const SolverBody* b) {
  // The plane's origin is the points' centroid; offsets from a body's centre are ra, rb.
  Vec3 ra0 = Vec3::Zero(), rb0 = Vec3::Zero();
  for (int i = 0; i < c.count; ++i) ra0 += c.points[i].ra, rb0 += c.points[i].rb;
  ra0 /= c.count;
  rb0 /= c.count;
  std::array<Vec3, kMaxContactPoints> offsets;
  for (int i = 0; i < c.count; ++i) offsets[i] = c.points[i].rb - rb0;
  Vec3 t1, t2;
  tangents(c.normal, t1, t2);
  ContactSide side_a, side_b;
  if (a) side_a = {a->inv_mass, a->inv_inertia, ra0};
  if (b) side_b = {b->inv_mass, b->inv_inertia, rb0};
  return make_normal_system(c.normal, t1, t2, offsets.data(), c.count, a ? &side_a : nullptr,
                            b ? &side_b : nullptr);
}

// Split impulse (Catto, GDC 2006 notes; Bullet's splitImpulse): penetration beyond the slop is
// removed by pseudo velocities that move the positions but never enter the momenta, so the
// correction adds no energy (Baumgarte's bias would make stacks bounce).
void Solver::solve_position(std::size_t slot) {
  const ContactRows& rows = rows_[slot];
  const ContactPointRows& points = point_rows_[slot];
  std::array<double, kMaxContactPoints>& pseudo = impulses_[slot].pseudo;
  SolverBody& a = at(rows.a);
  SolverBody& b = at(rows.b);
  const Vec3& n = rows.dir[0];
  for (int i = 0; i < rows.count; ++i) {
    const PointRows& r = points[i];
    // Pseudo velocities obey the contacts too (Solver::split_target_of, found once in prepare:
    // the separations are the step start's; `pile`'s 3 s, 192.5 M → 181.6 M instructions here).
    const double target = r.split_target;
    const double vn = n.dot(b.vp - a.vp) + b.wp.dot(r.ang_b) - a.wp.dot(r.ang_a);
    const double next = std::max(0.0, pseudo[i] + r.normal_mass * (target - vn));
    const double delta = next - pseudo[i];
    pseudo[i] = next;
    if (delta == 0.0) continue;
    if (a.inv_mass > 0.0) {  // not the floor, which contacts of one colour share
      a.vp -= (a.inv_mass * delta) * n;
      a.wp -= delta * r.inv_a;
    }
    b.vp += (b.inv_mass * delta) * n;
    b.wp += delta * r.inv_b;
  }
}

void Solver::finish(std::size_t begin, std::size_t end) {
  for (std::size_t k = begin; k < end; ++k) {
    Body& body = bodies_[ids_[k]];
    const SolverBody& s = sb_[k];
    body.s.P = body.c.mass * s.v;
    body.s.L = body.s.R * body.c.inertia.cwiseProduct(body.s.R.transpose() * s.w);
  }
}

void Solver::release() {
  for (std::uint32_t id : ids_) index_[id] = -1;
}

int floor_contact(const BodyState& s, const BodyConstants& c, std::uint32_t body,
                  double floor_y, double margin, Contact& out) {
  out.a = kStaticBody;
  out.b = body;
  out.normal = Vec3::UnitY();
  out.friction = c.friction;
  out.restitution = c.restitution;
  out.count = 0;
  out.friction_impulse = {};
  if (lowest_vertex_y(s, c) - floor_y >= margin) return 0;
  for (int i = 0; i < 8; ++i) {
    const Vec3 p = world_vertex(s, c, i);
    const double gap = p.y() - floor_y;
    if (gap >= margin) continue;
    ContactPoint& cp = out.points[out.count++];
    cp = ContactPoint{};
    cp.position = p;
    cp.separation = gap;
    cp.id = static_cast<std::uint32_t>(i);
  }
  return out.count;
}

// Points are matched by feature id; a point whose features changed (a vertex that slid past
// a clipping plane) takes the impulse of the nearest unmatched old point within
// kWarmStartDistance, as Bullet's persistent manifold does by position alone. The patch
// friction carries over while the normal (and so the tangents it fixes) has turned by less
// than kWarmStartCosine.
void warm_start_from(Contact& contact, const Contact& previous) {
  constexpr double kWarmStartDistance = 0.01;  // m
  constexpr double kWarmStartCosine = 0.99;    // about 8°
  if (contact.normal.dot(previous.normal) > kWarmStartCosine)
    contact.friction_impulse = previous.friction_impulse;
  std::array<bool, kMaxContactPoints> used{};
  std::array<bool, kMaxContactPoints> done{};
  for (int i = 0; i < contact.count; ++i) {
    ContactPoint& p = contact.points[i];
    for (int k = 0; k < previous.count; ++k) {
      if (used[k] || previous.points[k].id != p.id) continue;
      p.normal_impulse = previous.points[k].normal_impulse;
      used[k] = done[i] = true;
      break;
    }
  }
  for (int i = 0; i < contact.count; ++i) {
    if (done[i]) continue;
    ContactPoint& p = contact.points[i];
    int best = -1;
    double best_d2 = kWarmStartDistance * kWarmStartDistance;
    for (int k = 0; k < previous.count; ++k) {
      const double d2 = (previous.points[k].position - p.position).squaredNorm();
      if (!used[k] && d2 < best_d2) best = k, best_d2 = d2;
    }
    if (best < 0) continue;
    p.normal_impulse = previous.points[best].normal_impulse;
    used[best] = true;
  }
}

}  // namespace tumble
