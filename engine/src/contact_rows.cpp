/// The contact solver's rows of one step (Solver::prepare): each point's offsets and normal
/// row, the normal block in the patch's coordinates and the patch friction rows.
#include "solver.hpp"

namespace tumble {
namespace {

/// The patch friction rows of `rows` (FrictionRows): the tangents at the point ra0, rb0 (m,
/// from the centres) and the twist about the normal.
void prepare_friction(const Contact& c, ContactRows& rows, const SolverBody* a,
                      const SolverBody* b, const Vec3& ra0, const Vec3& rb0) {
  FrictionRows& f = rows.friction;
  const Vec3& n = rows.dir[0];
  for (int k = 0; k < 3; ++k) {
    const Vec3 ang_a = !a ? Vec3::Zero() : k < 2 ? Vec3(ra0.cross(rows.dir[k + 1])) : n;
    const Vec3 ang_b = k < 2 ? Vec3(rb0.cross(rows.dir[k + 1])) : n;
    if (k < 2) f.ang_a[k] = ang_a, f.ang_b[k] = ang_b;
    f.inv_a[k] = a ? Vec3(a->inv_inertia * ang_a) : Vec3::Zero();
    f.inv_b[k] = b->inv_inertia * ang_b;
    const double linear = k < 2 ? (a ? a->inv_mass : 0.0) + b->inv_mass : 0.0;
    f.mass[k] = 1.0 / (linear + ang_a.dot(f.inv_a[k]) + ang_b.dot(f.inv_b[k]));
  }
  f.radius = 0.0;
  for (int i = 0; i < c.count; ++i) {
    const Vec3 o = c.points[i].rb - rb0;
    f.radius += (o - o.dot(n) * n).norm();
  }
  f.radius /= c.count;
}

/// The normal block of `rows` (ContactRows): the columns C, D, G, P G and P Dᵀ target, with
/// K = D S Dᵀ formed from the columns (active_set.hpp: S = Σ Cᵀ I⁻¹ C + m⁻¹ e₀e₀ᵀ); `points`:
/// the contact's point rows, their targets set.
void prepare_block(const Contact& c, ContactRows& rows, const ContactPointRows& points,
                   const SolverBody* a, const SolverBody* b, const Vec3& ra0, const Vec3& rb0) {
  const Vec3& n = rows.dir[0];
  rows.ca = {a ? Vec3(ra0.cross(n)) : Vec3::Zero(), rows.dir[1].cross(n), rows.dir[2].cross(n)};
  rows.cb0 = rb0.cross(n);
  const std::array<Vec3, 3> cb = {rows.cb0, rows.ca[1], rows.ca[2]};
  for (int k = 0; k < 3; ++k) {
    rows.inv_ca[k] = a ? Vec3(a->inv_inertia * rows.ca[k]) : Vec3::Zero();
    rows.inv_cb[k] = b->inv_inertia * cb[k];
  }
  rows.D.resize(c.count, 3);
  // G = Σ dᵢ dᵢᵀ and Dᵀ target = Σ targetᵢ dᵢ, dᵢ = (1, αᵢ, βᵢ): by its sums (gram_of_sums).
  double sa = 0.0, sb = 0.0, saa = 0.0, sab = 0.0, sbb = 0.0;
  Vec3 dt_target = Vec3::Zero();
  for (int i = 0; i < c.count; ++i) {
    const Vec3 o = c.points[i].rb - rb0;
    const double alpha = o.dot(rows.dir[1]), beta = o.dot(rows.dir[2]);
    rows.D.row(i) << 1.0, alpha, beta;
    sa += alpha;
    sb += beta;
    saa += alpha * alpha;
    sab += alpha * beta;
    sbb += beta * beta;
    const double target = points[i].target;  // Solver::target_of, set by prepare
    dt_target(0) += target;
    dt_target(1) += target * alpha;
    dt_target(2) += target * beta;
  }
  rows.G = gram_of_sums(c.count, sa, sb, saa, sab, sbb);
  Mat3 P = Mat3::Zero();
  if (c.count == 1) {
    P(0, 0) = points[0].normal_mass;
  } else {
    Mat3 S;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        S(i, j) = rows.ca[i].dot(rows.inv_ca[j]) + cb[i].dot(rows.inv_cb[j]);
    S(0, 0) += (a ? a->inv_mass : 0.0) + b->inv_mass;
    P = pseudo_inverse_factor_of_gram(rows.G, S);
  }
  rows.PG = P * rows.G;
  rows.Pt = P * dt_target;
}

}  // namespace

void Solver::prepare(Contact& c, std::size_t slot, double dt, const SolverSettings& s) {
  SolverBody* a = body(c.a);
  SolverBody* b = body(c.b);
  ContactRows& block = rows_[slot];  // sized by the caller
  ContactPointRows& points = point_rows_[slot];
  block.a = c.a == kStaticBody ? -1 : index_[c.a];
  block.b = index_[c.b];
  block.count = c.count;
  block.mu = c.friction;
  ContactImpulses& impulses = impulses_[slot];
  impulses.friction = c.friction_impulse;
  tangents(c.normal, block.dir[1], block.dir[2]);
  block.dir[0] = c.normal;
  const Vec3& normal = c.normal;
  Vec3 ra0 = Vec3::Zero(), rb0 = Vec3::Zero();  // the points' centroid from each centre
  for (int i = 0; i < c.count; ++i) {
    ContactPoint& p = c.points[i];
    p.ra = c.a == kStaticBody ? p.position : Vec3(p.position - bodies_[c.a].s.x);
    p.rb = p.position - bodies_[c.b].s.x;
    ra0 += p.ra;
    rb0 += p.rb;
    PointRows& r = points[i];
    r.ang_a = a ? Vec3(p.ra.cross(normal)) : Vec3::Zero();
    r.inv_a = a ? Vec3(a->inv_inertia * r.ang_a) : Vec3::Zero();
    r.ang_b = p.rb.cross(normal);
    r.inv_b = b->inv_inertia * r.ang_b;
    const double k = (a ? a->inv_mass + r.ang_a.dot(r.inv_a) : 0.0) + b->inv_mass +
                     r.ang_b.dot(r.inv_b);  // n·K n, 1/kg
    r.normal_mass = 1.0 / k;
    r.target = target_of(p, dt);
    r.split_target = split_target_of(p, dt, s);
    impulses.normal[i] = p.normal_impulse;
    impulses.pseudo[i] = 0.0;
  }
  ra0 /= c.count;
  rb0 /= c.count;
  prepare_block(c, block, points, a, b, ra0, rb0);
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

void Solver::store_impulses(Contact& c, std::size_t slot) const {
  const ContactImpulses& impulses = impulses_[slot];
  for (int i = 0; i < c.count; ++i) c.points[i].normal_impulse = impulses.normal[i];
  c.friction_impulse = impulses.friction;
}

}  // namespace tumble
