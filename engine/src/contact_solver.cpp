#include "contact_solver.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "active_set.hpp"
#include "floor_contact.hpp"
#include "worker_pool.hpp"

namespace tumble {
namespace {

static_assert(kMaxContactPoints <= kMaxActiveSetPoints);

/// Two unit tangents completing n to a right-handed basis, chosen the same way every step so
/// accumulated friction impulses stay meaningful for warm starting.
void tangents(const Vec3& n, Vec3& t1, Vec3& t2) {
  const Vec3 ref = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  t1 = n.cross(ref).normalized();
  t2 = n.cross(t1);
}

/// A body's velocities during one contact's sweep (m/s, rad/s).
struct Motion {
  Vec3 v;
  Vec3 w;
};

class Solver {
 public:
  /// The solver bodies of `ids` with their velocities at the step start, gravity's
  /// `gravity_dv` (m/s) added to v.
  Solver(std::span<Body> bodies, std::span<const std::uint32_t> ids, SolverScratch& scratch,
         WorkerPool& pool, const Vec3& gravity_dv)
      : bodies_(bodies), ids_(ids), index_(scratch.index), sb_(scratch.bodies),
        rows_(scratch.rows), fixed_(scratch.fixed), order_(scratch.order),
        waves_(scratch.waves), wave_of_(scratch.wave_of), wave_start_(scratch.wave_start),
        wave_order_(scratch.wave_order), group_start_(scratch.group_start) {
    index_.resize(bodies.size(), -1);
    fixed_ = SolverBody{};
    sb_.resize(ids.size());
    pool.for_each(ids.size(), 128, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        const Body& b = bodies[ids[k]];
        index_[ids[k]] = static_cast<std::int32_t>(k);
        sb_[k] = SolverBody{};
        sb_[k].inv_mass = b.c.inv_mass;
        sb_[k].inv_inertia = inverse_inertia_world(b.s, b.c);
        sb_[k].v = b.s.P * b.c.inv_mass;
        sb_[k].w = sb_[k].inv_inertia * b.s.L;
        sb_[k].v += gravity_dv;
      }
    });
  }

  SolverBody* body(std::uint32_t id) { return id == kStaticBody ? nullptr : &sb_[index_[id]]; }

  static Vec3 point_velocity(const SolverBody* s, const Vec3& r) {
    return s ? Vec3(s->v + s->w.cross(r)) : Vec3::Zero();
  }
  static Vec3 pseudo_velocity(const SolverBody* s, const Vec3& r) {
    return s ? Vec3(s->vp + s->wp.cross(r)) : Vec3::Zero();
  }
  /// Impulse j (N·s) on b at rb, −j on a at ra.
  static void apply(SolverBody* a, SolverBody* b, const Vec3& ra, const Vec3& rb, const Vec3& j) {
    if (a) a->v -= a->inv_mass * j, a->w -= a->inv_inertia * ra.cross(j);
    if (b) b->v += b->inv_mass * j, b->w += b->inv_inertia * rb.cross(j);
  }
  static void apply_pseudo(SolverBody* a, SolverBody* b, const Vec3& ra, const Vec3& rb,
                           const Vec3& j) {
    if (a) a->vp -= a->inv_mass * j, a->wp -= a->inv_inertia * ra.cross(j);
    if (b) b->vp += b->inv_mass * j, b->wp += b->inv_inertia * rb.cross(j);
  }
  void prepare(Contact& c, std::size_t n, double dt) {
    SolverBody* a = body(c.a);
    SolverBody* b = body(c.b);
    ContactRows& block = rows_[n];  // sized by the caller
    tangents(c.normal, block.dir[1], block.dir[2]);
    block.dir[0] = c.normal;
    const Vec3& normal = c.normal;
    Vec3 ra0 = Vec3::Zero(), rb0 = Vec3::Zero();  // the points' centroid from each centre
    for (int i = 0; i < c.count; ++i) {
      ContactPoint& p = c.points[i];
      p.ra = c.a == kStaticBody ? p.position : Vec3(p.position - bodies_[c.a].s.x);
      p.rb = p.position - bodies_[c.b].s.x;
      p.pseudo_impulse = 0.0;
      ra0 += p.ra;
      rb0 += p.rb;
      PointRows& r = block.points[i];
      r.ang_a = a ? Vec3(p.ra.cross(normal)) : Vec3::Zero();
      r.inv_a = a ? Vec3(a->inv_inertia * r.ang_a) : Vec3::Zero();
      r.ang_b = p.rb.cross(normal);
      r.inv_b = b->inv_inertia * r.ang_b;
      const double k = (a ? a->inv_mass + r.ang_a.dot(r.inv_a) : 0.0) + b->inv_mass +
                       r.ang_b.dot(r.inv_b);  // n·K n, 1/kg
      p.normal_mass = 1.0 / k;
    }
    ra0 /= c.count;
    rb0 /= c.count;
    prepare_block(c, block, a, b, ra0, rb0, dt);
    // Friction acts at the patch's centre of pressure (see solve_friction).
    double load = 0.0;
    Vec3 ra_load = Vec3::Zero(), rb_load = Vec3::Zero();
    for (int i = 0; i < c.count; ++i) {
      load += c.points[i].normal_impulse;
      ra_load += c.points[i].normal_impulse * c.points[i].ra;
      rb_load += c.points[i].normal_impulse * c.points[i].rb;
    }
    if (load > 0.0) prepare_friction(c, block, a, b, ra_load / load, rb_load / load);
    else prepare_friction(c, block, a, b, ra0, rb0);
  }

  /// The patch friction rows of `rows` (FrictionRows): the tangents at the point ra0, rb0 (m,
  /// from the centres) and the twist about the normal.
  static void prepare_friction(const Contact& c, ContactRows& rows, const SolverBody* a,
                               const SolverBody* b, const Vec3& ra0, const Vec3& rb0) {
    FrictionRows& f = rows.friction;
    const Vec3& n = rows.dir[0];
    for (int k = 0; k < 3; ++k) {
      f.ang_a[k] = !a ? Vec3::Zero() : k < 2 ? Vec3(ra0.cross(rows.dir[k + 1])) : n;
      f.ang_b[k] = k < 2 ? Vec3(rb0.cross(rows.dir[k + 1])) : n;
      f.inv_a[k] = a ? Vec3(a->inv_inertia * f.ang_a[k]) : Vec3::Zero();
      f.inv_b[k] = b->inv_inertia * f.ang_b[k];
      const double linear = k < 2 ? (a ? a->inv_mass : 0.0) + b->inv_mass : 0.0;
      f.mass[k] = 1.0 / (linear + f.ang_a[k].dot(f.inv_a[k]) + f.ang_b[k].dot(f.inv_b[k]));
    }
    f.radius = 0.0;
    for (int i = 0; i < c.count; ++i) {
      const Vec3 o = c.points[i].rb - rb0;
      f.radius += (o - o.dot(n) * n).norm();
    }
    f.radius /= c.count;
  }

  /// The normal block of `rows` (ContactRows): the columns C, D, G, P G and P Dᵀ target, with
  /// K = D S Dᵀ formed from the columns (active_set.hpp: S = Σ Cᵀ I⁻¹ C + m⁻¹ e₀e₀ᵀ).
  static void prepare_block(const Contact& c, ContactRows& rows, const SolverBody* a,
                            const SolverBody* b, const Vec3& ra0, const Vec3& rb0, double dt) {
    const Vec3& n = rows.dir[0];
    rows.ca = {a ? Vec3(ra0.cross(n)) : Vec3::Zero(), rows.dir[1].cross(n), rows.dir[2].cross(n)};
    rows.cb = {rb0.cross(n), rows.ca[1], rows.ca[2]};
    for (int k = 0; k < 3; ++k) {
      rows.inv_ca[k] = a ? Vec3(a->inv_inertia * rows.ca[k]) : Vec3::Zero();
      rows.inv_cb[k] = b->inv_inertia * rows.cb[k];
    }
    rows.D.resize(c.count, 3);
    rows.G.setZero();
    Vec3 dt_target = Vec3::Zero();
    for (int i = 0; i < c.count; ++i) {
      const Vec3 o = c.points[i].rb - rb0;
      const Vec3 d(1.0, o.dot(rows.dir[1]), o.dot(rows.dir[2]));
      rows.D.row(i) = d.transpose();
      rows.G.noalias() += d * d.transpose();
      dt_target += target_of(c.points[i], dt) * d;
    }
    Mat3 P = Mat3::Zero();
    if (c.count == 1) {
      P(0, 0) = c.points[0].normal_mass;
    } else {
      Mat3 S;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) S(i, j) = rows.ca[i].dot(rows.inv_ca[j]) + rows.cb[i].dot(rows.inv_cb[j]);
      S(0, 0) += (a ? a->inv_mass : 0.0) + b->inv_mass;
      P = pseudo_inverse_factor_of_gram(rows.G, S);
    }
    rows.PG = P * rows.G;
    rows.Pt = P * dt_target;
  }

  int impact(Contact& c, const Vec3& gravity, double dt);
  void shock_propagation(std::span<Contact> contacts, const Vec3& gravity, double dt,
                         WorkerPool& pool);
  void push_up(Contact& c, const Vec3& up, double dt);
  void push_up_body(std::span<Contact> contacts,
                    std::span<const std::pair<double, std::uint32_t>> group, const Vec3& up,
                    double dt);
  /// The body a support contact holds up (the one the normal, oriented up, points into).
  static std::uint32_t upper_of(const Contact& c, const Vec3& up) {
    return c.normal.dot(up) > 0.0 ? c.b : c.a;
  }
  /// K = D S Dᵀ, K_ij = n·(change of the relative normal velocity at point i per unit impulse
  /// at j), 1/kg; a or b null: that body is held fixed.
  static NormalSystem normal_system_of(const Contact& c, const SolverBody* a,
                                       const SolverBody* b);
  void warm_start(Contact& c, std::size_t index);
  void solve_velocity(Contact& c, std::size_t index, double dt);
  /// The sweep of one contact on velocities held in locals.
  static void solve_velocity_rows(Contact& c, const ContactRows& rows, Motion& a, Motion& b,
                                  double ma, double mb, double dt);
  void solve_position(Contact& c, std::size_t index, const SolverSettings& s, double dt);
  /// The solver body of id, or the fixed stand-in for the floor.
  SolverBody& side(std::uint32_t id) { return id == kStaticBody ? fixed_ : sb_[index_[id]]; }
  /// Relative normal velocity of b over a at a point (row r, normal n), m/s. Body: anything
  /// with velocities v and w (a SolverBody, or a Motion held in registers).
  template <typename Body>
  static double normal_speed(const Body& a, const Body& b, const Vec3& n, const PointRows& r) {
    return n.dot(b.v - a.v) + b.w.dot(r.ang_b) - a.w.dot(r.ang_a);
  }
  /// Normal impulse j (N·s) at a point: +j n on b, −j n on a (inverse masses ma, mb in 1/kg;
  /// ma = 0: a is the floor and keeps its zero velocity).
  template <typename Body>
  static void push(Body& a, Body& b, double ma, double mb, const Vec3& n, const PointRows& r,
                   double j) {
    if (j == 0.0) return;
    if (ma > 0.0) {
      a.v -= (ma * j) * n;
      a.w -= j * r.inv_a;
    }
    b.v += (mb * j) * n;
    b.w += j * r.inv_b;
  }
  /// The patch friction of one contact on velocities held in locals (see solve_velocity).
  static void solve_friction(Contact& c, const ContactRows& rows, Motion& a, Motion& b,
                             double ma, double mb);
  /// The block step of the normal impulses of a contact of two or more points; false (and
  /// nothing changed) when it would pull at a point.
  static bool solve_normal_block(Contact& c, const ContactRows& rows, Motion& a, Motion& b,
                                 double ma, double mb);
  /// Writes the end-of-step momenta P = m v, L = I w (I at the step start) of solver bodies
  /// [begin, end).
  void finish(std::size_t begin, std::size_t end);
  /// Forgets the body index, so the next step starts from an index of −1 only.
  void release();
  /// Normal velocity a point must reach: a speculative point may close its gap within the
  /// step, a touching one may not approach (its penetration is the split impulse's job).
  static double target_of(const ContactPoint& p, double dt) {
    return p.separation > 0.0 ? -p.separation / dt : 0.0;
  }

 private:
  std::span<Body> bodies_;
  std::span<const std::uint32_t> ids_;
  std::vector<std::int32_t>& index_;
  std::vector<SolverBody>& sb_;
  std::vector<ContactRows>& rows_;  // solver rows of each contact
  SolverBody& fixed_;               // the floor: absorbs impulses without moving
  std::vector<std::pair<double, std::uint32_t>>& order_;
  std::vector<std::uint32_t>& waves_;       // latest shock-propagation wave of each body
  std::vector<std::uint32_t>& wave_of_;     // wave of each group
  std::vector<std::uint32_t>& wave_start_;  // start of each wave in wave_order_
  std::vector<std::uint32_t>& wave_order_;  // solves (groups), wave by wave
  std::vector<std::uint32_t>& group_start_;  // start of each body's supports in order_
};

// The collision pass of Guendelman, Bridson & Fedkiw 2003 (§5), with each contact's impact
// solved exactly rather than iterated: the points of one contact that touch within the step
// and approach faster than the restitution threshold get simultaneous normal impulses that
// leave every active point with v⁺ₙ = −e v⁻ₙ (an active-set solve as in Baraff 1989, §4, with
// the pseudo-inverse for a rank-deficient face patch). With e = 1 the kinetic energy change
// Σ jᵢ (v⁻ᵢ + v⁺ᵢ)/2 is zero and the pair's momentum changes by ±Σ jᵢ n: both are conserved to
// round-off, as for an isolated impact with the floor. Frictionless: friction acts in the
// contact pass that follows.
int Solver::impact(Contact& c, const Vec3& gravity, double dt) {
  SolverBody* a = body(c.a);
  SolverBody* b = body(c.b);
  const double rest = rest_speed(c.restitution, gravity, dt);
  const double threshold = std::max(rest, 2.0 * gravity.norm() * dt);
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

void Solver::warm_start(Contact& c, std::size_t index) {
  SolverBody& a = side(c.a);
  SolverBody& b = side(c.b);
  const ContactRows& rows = rows_[index];
  for (int i = 0; i < c.count; ++i)
    push(a, b, a.inv_mass, b.inv_mass, rows.dir[0], rows.points[i], c.points[i].normal_impulse);
  const FrictionRows& f = rows.friction;
  const std::array<double, 3>& j = c.friction_impulse;
  const Vec3 linear = j[0] * rows.dir[1] + j[1] * rows.dir[2];
  if (a.inv_mass > 0.0) {
    a.v -= a.inv_mass * linear;
    a.w -= j[0] * f.inv_a[0] + j[1] * f.inv_a[1] + j[2] * f.inv_a[2];
  }
  b.v += b.inv_mass * linear;
  b.w += j[0] * f.inv_b[0] + j[1] * f.inv_b[1] + j[2] * f.inv_b[2];
}

// Sequential impulses (Catto, "Iterative dynamics with temporal coherence", GDC 2005, and
// "Fast and simple physics using sequential impulses", GDC 2006): each point in turn gets the
// impulse that fixes its own relative velocity, the accumulated total is clamped (normal
// ≥ 0, friction inside the disc of radius μ λₙ) rather than each increment, and the totals
// start from the previous step's (warm starting), so a stack's static impulses carry over and
// only their change has to converge. Speculative points (Catto GDC 2013; Box2D, Jolt) may
// approach by their gap within the step but no more, so a falling body stops at the surface
// instead of penetrating first.
void Solver::solve_velocity(Contact& c, std::size_t index, double dt) {
  SolverBody& body_a = side(c.a);
  SolverBody& body_b = side(c.b);
  // The two bodies' velocities in locals for the whole contact: the compiler keeps them in
  // registers instead of storing them after every row (a third of the sweep's instructions).
  Motion a{body_a.v, body_a.w}, b{body_b.v, body_b.w};
  const double ma = body_a.inv_mass, mb = body_b.inv_mass;
  solve_velocity_rows(c, rows_[index], a, b, ma, mb, dt);
  if (ma > 0.0) body_a.v = a.v, body_a.w = a.w;  // not the floor, which a colour's contacts share
  body_b.v = b.v;
  body_b.w = b.w;
}

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
void Solver::solve_friction(Contact& c, const ContactRows& rows, Motion& a, Motion& b,
                            double ma, double mb) {
  const FrictionRows& f = rows.friction;
  double load = 0.0;
  for (int i = 0; i < c.count; ++i) load += c.points[i].normal_impulse;
  const double limit = c.friction * load;
  std::array<double, 3>& total = c.friction_impulse;
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
    total[2] = std::clamp(old2 - f.mass[2] * (b.w.dot(f.ang_b[2]) - a.w.dot(f.ang_a[2])),
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
bool Solver::solve_normal_block(Contact& c, const ContactRows& rows, Motion& a, Motion& b,
                                double ma, double mb) {
  const int n = c.count;
  const Vec3 wr = b.w - a.w;
  const Vec3 y(rows.dir[0].dot(b.v - a.v) + b.w.dot(rows.cb[0]) - a.w.dot(rows.ca[0]),
               wr.dot(rows.ca[1]), wr.dot(rows.ca[2]));
  const Vec3 z = rows.Pt - rows.PG * y;
  std::array<double, kMaxContactPoints> next{};
  bool pushes = true;
  for (int i = 0; i < n; ++i) {
    next[i] = c.points[i].normal_impulse + rows.D.row(i).dot(z);
    pushes = pushes && next[i] >= 0.0;
  }
  if (pushes) {
    for (int i = 0; i < n; ++i) c.points[i].normal_impulse = next[i];
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

void Solver::solve_velocity_rows(Contact& c, const ContactRows& rows, Motion& a, Motion& b,
                                 double ma, double mb, double dt) {
  solve_friction(c, rows, a, b, ma, mb);
  const int n = c.count;
  // One point: the clamped sweep below is the block step.
  if (n > 1 && solve_normal_block(c, rows, a, b, ma, mb)) return;
  for (int i = 0; i < n; ++i) {
    ContactPoint& p = c.points[i];
    const double vn = normal_speed(a, b, rows.dir[0], rows.points[i]);
    const double next_i = std::max(0.0, p.normal_impulse - p.normal_mass * (vn - target_of(p, dt)));
    const double delta = next_i - p.normal_impulse;
    p.normal_impulse = next_i;
    push(a, b, ma, mb, rows.dir[0], rows.points[i], delta);
  }
}

// Shock propagation (Guendelman, Bridson & Fedkiw 2003, §7): after the iterations, one sweep
// over the bodies from the ground up in which each body's supports count as immovable, so it
// alone takes whatever approach the unconverged iterations left. A stack then cannot sink
// however tall it is, even on the first step before warm starting has built its impulses, and
// a heavy body on a light one cannot crush it. The sweep only pushes (never pulls) and only
// where a contact still approaches, so an impact already resolved exactly, or a scene without
// gravity (no "up"), is untouched.
//
// A body's support contacts are solved together, as one active-set solve over all their
// points (they share a normal when the body rests flat on several others). Solved one after
// another, each pushed the body up at one side and tipped it; the next support then had to
// push the other side up further, and the body left faster than every support under it. Up a
// 100-row pyramid that ratchet added up to 0.7 m/s at the top in the first step and threw the
// upper rows off.
//
// The impulses of the sweep join the points' accumulated normal impulses, so they warm start
// the next step: the iterations then begin from a support that already holds the stack up,
// and the friction bound μ Σλₙ of each patch covers the load it carries. Kept out of the
// totals, the sweep's share had to be found again every step, the iterations never held a tall
// stack, and pyramid_large (5,050 boxes) crept sideways until it fell; with them it stands
// (its top box moves 3.4 cm) and sleeps within 2 s.
//
// The sweep is ordered, but a body's solve depends only on the earlier solves that share one
// of its bodies: each solve's wave is one more than the latest wave of its bodies, and the
// solves of one wave touch disjoint bodies. Waves run in turn, each shared among the pool's
// threads: every body sees the same updates in the same order as in the ordered sweep.
void Solver::shock_propagation(std::span<Contact> contacts, const Vec3& gravity, double dt,
                               WorkerPool& pool) {
  constexpr double kSupportCosine = 0.3;  // |n·up| below this: a side contact (> 72° from up)
  const double g = gravity.norm();
  if (g == 0.0) return;
  const Vec3 up = -gravity / g;
  std::vector<std::pair<double, std::uint32_t>>& order = order_;
  order.clear();
  for (std::size_t i = 0; i < contacts.size(); ++i)
    // A contact whose normal is nearly horizontal supports nothing and is left to the
    // iterations.
    if (std::abs(contacts[i].normal.dot(up)) >= kSupportCosine)
      order.emplace_back(up.dot(bodies_[upper_of(contacts[i], up)].s.x),
                         static_cast<std::uint32_t>(i));
  // By the height of the supported body, its contacts together (in contact order).
  std::sort(order.begin(), order.end(), [&](const auto& p, const auto& q) {
    if (p.first != q.first) return p.first < q.first;
    const std::uint32_t up_p = upper_of(contacts[p.second], up);
    const std::uint32_t up_q = upper_of(contacts[q.second], up);
    return up_p != up_q ? up_p < up_q : p.second < q.second;
  });
  group_start_.clear();
  for (std::size_t k = 0; k < order.size(); ++k)
    if (k == 0 || upper_of(contacts[order[k].second], up) !=
                      upper_of(contacts[order[k - 1].second], up))
      group_start_.push_back(static_cast<std::uint32_t>(k));
  const std::size_t groups = group_start_.size();
  group_start_.push_back(static_cast<std::uint32_t>(order.size()));
  auto solve_group = [&](std::size_t gi) {
    push_up_body(contacts, {order.data() + group_start_[gi], order.data() + group_start_[gi + 1]},
                 up, dt);
  };
  if (pool.size() == 1) {  // the height order itself: what the waves replay
    for (std::size_t gi = 0; gi < groups; ++gi) solve_group(gi);
    return;
  }
  waves_.assign(sb_.size(), 0);
  wave_of_.resize(groups);
  std::uint32_t last = 0;
  for (std::size_t gi = 0; gi < groups; ++gi) {
    std::uint32_t wave = 0;
    auto each_body = [&](auto&& fn) {
      for (std::uint32_t k = group_start_[gi]; k < group_start_[gi + 1]; ++k) {
        const Contact& c = contacts[order[k].second];
        if (c.a != kStaticBody) fn(waves_[index_[c.a]]);
        fn(waves_[index_[c.b]]);
      }
    };
    each_body([&](std::uint32_t w) { wave = std::max(wave, w); });
    ++wave;
    each_body([&](std::uint32_t& w) { w = wave; });
    wave_of_[gi] = wave;
    last = std::max(last, wave);
  }
  // Counting sort of the groups by wave (stable: height order within a wave).
  wave_start_.assign(last + 2, 0);
  for (std::uint32_t w : wave_of_) ++wave_start_[w + 1];
  for (std::size_t w = 1; w < wave_start_.size(); ++w) wave_start_[w] += wave_start_[w - 1];
  wave_order_.resize(groups);
  for (std::size_t gi = 0; gi < groups; ++gi)
    wave_order_[wave_start_[wave_of_[gi]]++] = static_cast<std::uint32_t>(gi);
  for (std::size_t w = wave_start_.size() - 1; w > 0; --w) wave_start_[w] = wave_start_[w - 1];
  wave_start_[0] = 0;
  for (std::uint32_t w = 1; w <= last; ++w) {
    const std::size_t begin = wave_start_[w], end = wave_start_[w + 1];
    pool.for_each(end - begin, 16, [&](std::size_t from, std::size_t to) {
      for (std::size_t k = begin + from; k < begin + to; ++k) solve_group(wave_order_[k]);
    });
  }
}

/// Shock propagation of one body on its supports (`group`: (height, contact) entries whose
/// contacts all hold the body up): the supports held fixed, the body alone takes the approach
/// the iterations left, over all the points at once when they share a normal (else contact by
/// contact, as when they do not fit one solve).
void Solver::push_up_body(std::span<Contact> contacts,
                          std::span<const std::pair<double, std::uint32_t>> group,
                          const Vec3& up, double dt) {
  constexpr double kParallel = 1.0 - 1e-9;  // cosine between normals solved as one
  const Contact& first = contacts[group[0].second];
  const Vec3 n = first.normal.dot(up) > 0.0 ? first.normal : Vec3(-first.normal);
  int m = 0;
  bool together = group.size() > 1;
  for (const auto& [h, i] : group) {
    const Contact& c = contacts[i];
    m += c.count;
    together = together && std::abs(c.normal.dot(n)) >= kParallel;
  }
  if (!together || m > kMaxActiveSetPoints) {
    for (const auto& [h, i] : group) push_up(contacts[i], up, dt);
    return;
  }
  const std::uint32_t id = upper_of(first, up);
  SolverBody* upper = body(id);
  std::array<Vec3, kMaxActiveSetPoints> r;  // points from the body's centre, m
  std::array<ContactPoint*, kMaxActiveSetPoints> points{};
  PointVector vn(m), target(m);
  bool approaching = false;
  int k = 0;
  for (const auto& [h, i] : group) {
    Contact& c = contacts[i];
    const bool upper_is_b = c.b == id;
    const SolverBody* support = body(upper_is_b ? c.a : c.b);
    for (int q = 0; q < c.count; ++q, ++k) {
      ContactPoint& p = c.points[q];
      points[k] = &p;
      r[k] = upper_is_b ? p.rb : p.ra;
      const Vec3 rs = upper_is_b ? p.ra : p.rb;
      vn(k) = (point_velocity(upper, r[k]) - point_velocity(support, rs)).dot(n);
      target(k) = target_of(p, dt);
      approaching = approaching || vn(k) < target(k) - 1e-9;
    }
  }
  if (!approaching) return;
  Vec3 origin = Vec3::Zero();
  for (int q = 0; q < m; ++q) origin += r[q];
  origin /= m;
  std::array<Vec3, kMaxActiveSetPoints> offsets;
  for (int q = 0; q < m; ++q) offsets[q] = r[q] - origin;
  Vec3 t1, t2;
  tangents(n, t1, t2);
  const ContactSide side{upper->inv_mass, upper->inv_inertia, origin};
  const NormalSystem sys = make_normal_system(n, t1, t2, offsets.data(), m, nullptr, &side);
  ActiveSetCache cache(sys);  // keeps a reference to sys
  const PointVector impulse = solve_active_set(cache, vn, target);
  for (int q = 0; q < m; ++q) {
    if (impulse(q) <= 0.0) continue;
    apply(nullptr, upper, Vec3::Zero(), r[q], impulse(q) * n);
    points[q]->normal_impulse += impulse(q);  // warm starts the next step (see above)
  }
}

/// One contact of shock propagation: the lower body held fixed, the upper one alone takes the
/// approach the iterations left.
void Solver::push_up(Contact& c, const Vec3& up, double dt) {
  const bool a_lower = c.normal.dot(up) > 0.0;
  SolverBody* a = a_lower ? nullptr : body(c.a);
  SolverBody* b = a_lower ? body(c.b) : nullptr;
  const int n = c.count;
  PointVector vn(n), target(n);
  bool approaching = false;
  for (int k = 0; k < n; ++k) {
    const ContactPoint& p = c.points[k];
    vn(k) = (point_velocity(body(c.b), p.rb) - point_velocity(body(c.a), p.ra)).dot(c.normal);
    target(k) = target_of(p, dt);
    approaching = approaching || vn(k) < target(k) - 1e-9;
  }
  if (!approaching) return;
  const NormalSystem sys = normal_system_of(c, a, b);
  ActiveSetCache cache(sys);
  const PointVector impulse = solve_active_set(cache, vn, target);
  for (int k = 0; k < n; ++k) {
    if (impulse(k) <= 0.0) continue;
    apply(a, b, c.points[k].ra, c.points[k].rb, impulse(k) * c.normal);
    c.points[k].normal_impulse += impulse(k);  // warm starts the next step
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
void Solver::solve_position(Contact& c, std::size_t index, const SolverSettings& s, double dt) {
  SolverBody& a = side(c.a);
  SolverBody& b = side(c.b);
  const ContactRows& rows = rows_[index];
  const Vec3& n = rows.dir[0];
  for (int i = 0; i < c.count; ++i) {
    ContactPoint& p = c.points[i];
    const PointRows& r = rows.points[i];
    // Pseudo velocities obey the contacts too: a touching point may not be pushed deeper by
    // the correction of another contact (a box pressed into the floor by the one above it).
    const double target = p.separation > 0.0
                              ? -p.separation / dt
                              : s.position_gain * std::max(-p.separation - s.slop, 0.0) / dt;
    const double vn = n.dot(b.vp - a.vp) + b.wp.dot(r.ang_b) - a.wp.dot(r.ang_a);
    const double next = std::max(0.0, p.pseudo_impulse + p.normal_mass * (target - vn));
    const double delta = next - p.pseudo_impulse;
    p.pseudo_impulse = next;
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

}  // namespace

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

namespace {

/// Runs fn(contact, index) over the contacts colour by colour, each colour shared among the
/// pool's threads (its contacts touch disjoint bodies).
template <typename Fn>
void sweep(const ContactColours& colours, std::span<Contact> contacts, WorkerPool& pool,
           Fn&& fn) {
  constexpr std::size_t kGrain = 32;  // contacts per chunk: 0.1–0.5 µs each
  if (pool.size() == 1) {  // contact order: what the colours replay, without their cost
    for (std::size_t i = 0; i < contacts.size(); ++i) fn(contacts[i], i);
    return;
  }
  for (std::size_t k = 0; k < colours.count(); ++k) {
    const std::span<const std::uint32_t> colour = colours.of(k);
    pool.for_each(colour.size(), kGrain, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) fn(contacts[colour[i]], colour[i]);
    });
  }
}

/// True when some point of the contacts penetrates deeper than `slop` (m).
bool deeper_than(std::span<const Contact> contacts, double slop) {
  for (const Contact& c : contacts)
    for (int i = 0; i < c.count; ++i)
      if (-c.points[i].separation > slop) return true;
  return false;
}

}  // namespace

// The velocities of the bodies in contact, in the order of Guendelman, Bridson & Fedkiw 2003:
// gravity, the collision pass (impacts with restitution), the contact pass (sequential
// impulses, e = 0); positions then follow in flight with the corrected velocities
// (semi-implicit Euler), the split-impulse pseudo velocities added to the positions only.
// On several threads every pass but shock propagation (ordered by height, in waves) sweeps the
// contacts colour by colour, which replays the sweep in contact order that one thread runs.
int solve_contacts(std::span<Body> bodies, std::span<const std::uint32_t> solver_bodies,
                   std::span<Contact> contacts, const Vec3& gravity, double dt,
                   const SolverSettings& settings, SolverScratch& scratch, WorkerPool& pool) {
  constexpr std::size_t kBodyGrain = 128;
  Solver solver(bodies, solver_bodies, scratch, pool, dt * gravity);
  scratch.colours.offset.clear();  // one thread: no colours, the sweeps go in contact order
  if (pool.size() > 1) {
    scratch.colour_a.resize(contacts.size());
    scratch.colour_b.resize(contacts.size());
    for (std::size_t i = 0; i < contacts.size(); ++i) {
      scratch.colour_a[i] = contacts[i].a == kStaticBody ? -1 : scratch.index[contacts[i].a];
      scratch.colour_b[i] = scratch.index[contacts[i].b];
    }
    colour_contacts(scratch.colour_a, scratch.colour_b, solver_bodies.size(), scratch.colours);
  }
  if (scratch.rows.size() < contacts.size()) scratch.rows.resize(contacts.size());
  pool.for_each(contacts.size(), 32, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) solver.prepare(contacts[i], i, dt);
  });
  const ContactColours& colours = scratch.colours;
  std::atomic<int> impacts{0};
  sweep(colours, contacts, pool, [&](Contact& c, std::size_t) {
    if (solver.impact(c, gravity, dt)) impacts.fetch_add(1, std::memory_order_relaxed);
  });
  sweep(colours, contacts, pool, [&](Contact& c, std::size_t i) { solver.warm_start(c, i); });
  for (int it = 0; it < settings.velocity_iterations; ++it)
    sweep(colours, contacts, pool, [&](Contact& c, std::size_t i) { solver.solve_velocity(c, i, dt); });
  if (settings.shock_propagation) solver.shock_propagation(contacts, gravity, dt, pool);
  // The split impulse starts from zero pseudo velocities and only pushes: while no point is
  // deeper than the slop every target is ≤ 0 and every sweep would leave all of them zero (a
  // resting stack: `pyramid` spent 6 % of its instructions proving that).
  if (deeper_than(contacts, settings.slop))
    for (int it = 0; it < settings.position_iterations; ++it)
      sweep(colours, contacts, pool,
            [&](Contact& c, std::size_t i) { solver.solve_position(c, i, settings, dt); });
  pool.for_each(solver_bodies.size(), kBodyGrain,
                [&](std::size_t begin, std::size_t end) { solver.finish(begin, end); });
  solver.release();
  return impacts.load();
}

}  // namespace tumble
