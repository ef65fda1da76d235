#pragma once
/// The contact solver's working object, shared by the files of the solve (contact_passes.cpp,
/// contact_solver.cpp, contact_rows.cpp, shock_propagation.cpp); not part of the engine's
/// interface.
#include <cmath>
#include <span>
#include <utility>
#include <vector>

#include "active_set.hpp"
#include "contact_solver.hpp"
#include "worker_pool.hpp"

namespace tumble {

/// A job that reads and writes nothing shock propagation does, to run on one thread while
/// the others start shock propagation (Solver::shock_propagation): run(arg), once.
struct BesideJob {
  void (*run)(void*) = nullptr;  ///< Null: no job.
  void* arg = nullptr;           ///< What run is called with.
};

/// A body's velocities during one contact's sweep (m/s, rad/s).
struct Motion {
  Vec3 v;
  Vec3 w;
};

/// One step's contact solve over the solver bodies: their velocities, the contacts' rows and
/// the passes of solve_contacts (contact_passes.cpp), the rows (contact_rows.cpp) and shock
/// propagation (shock_propagation.cpp). Lives for one call of solve_contacts; its buffers are
/// the caller's SolverScratch. A pass over contacts of one colour may run on several threads.
class Solver {
 public:
  /// The solver bodies of `ids` with their velocities at the step start, gravity's
  /// `gravity_dv` (m/s) added to v.
  Solver(std::span<Body> bodies, std::span<const std::uint32_t> ids, SolverScratch& scratch,
         WorkerPool& pool, const Vec3& gravity_dv)
      : bodies_(bodies), ids_(ids), index_(scratch.index), sb_(scratch.bodies),
        rows_(scratch.rows), point_rows_(scratch.point_rows), impulses_(scratch.impulses),
        fixed_(scratch.fixed),
        supports_(scratch.supports), support_start_(scratch.support_start),
        support_keys_(scratch.support_keys), order_(scratch.order), waves_(scratch.waves),
        wave_of_(scratch.wave_of), wave_start_(scratch.wave_start), wave_order_(scratch.wave_order),
        touches_(scratch.touches), turn_base_(scratch.turn_base), upper_turn_(scratch.upper_turn),
        group_start_(scratch.group_start) {
    index_.resize(bodies.size(), -1);
    fixed_ = SolverBody{};
    sb_.resize(ids.size());
    turn_base_.assign(ids.size(), 0);
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

  /// The solver body of id, or null for the floor.
  SolverBody* body(std::uint32_t id) { return id == kStaticBody ? nullptr : &sb_[index_[id]]; }

  /// Velocity of the point at r from the centre of s (zero for the floor), m/s.
  static Vec3 point_velocity(const SolverBody* s, const Vec3& r) {
    return s ? Vec3(s->v + s->w.cross(r)) : Vec3::Zero();
  }
  /// Impulse j (N·s) on b at rb, −j on a at ra.
  static void apply(SolverBody* a, SolverBody* b, const Vec3& ra, const Vec3& rb, const Vec3& j) {
    if (a) a->v -= a->inv_mass * j, a->w -= a->inv_inertia * ra.cross(j);
    if (b) b->v += b->inv_mass * j, b->w += b->inv_inertia * rb.cross(j);
  }
  /// The step's rows of contact `c` in rows slot `slot`: the points' offsets and normal rows,
  /// the normal block, the patch friction and the accumulated impulses (contact_rows.cpp).
  /// Thread-safe across contacts.
  void prepare(Contact& c, std::size_t slot, double dt, const SolverSettings& s);
  /// Puts the accumulated impulses of rows slot `slot` back into its contact c.
  void store_impulses(Contact& c, std::size_t slot) const;

  /// The collision pass of contact c (rows slot `slot`): its fast-approaching points' exact
  /// impulses; 1 when it had an impact, else 0.
  int impact(Contact& c, std::size_t slot, const Vec3& gravity, double dt);
  /// False when no point of rows slot `slot` approaches faster than `threshold` (m/s) by
  /// more than round-off: the collision pass has nothing to do.
  bool may_be_fast(std::size_t slot, double threshold);
  /// The ground-up pass over the contacts after the iterations (shock_propagation.cpp), and
  /// `beside` (if any) once, on whichever thread takes it first; that thread then joins the
  /// pass where the others have got to.
  void shock_propagation(std::span<Contact> contacts, const Vec3& gravity, double dt,
                         WorkerPool& pool, BesideJob beside = {});
  /// Shock propagation's order (its supports by height and, with several threads, its
  /// waves), found on this thread alone; shock_propagation then uses it. Reads no velocity,
  /// so it may run beside the velocity sweeps.
  void plan_shock_propagation(std::span<const Contact> contacts, const Vec3& gravity);
  /// Shock propagation's entry of contacts [begin, end) into supports_ (sized to the
  /// contacts; upper kStaticBody: not a support). Thread-safe across ranges.
  void find_supports(std::span<const Contact> contacts, const Vec3& up, std::size_t begin,
                     std::size_t end);
  /// From the supports found: their order by height and, with `waves`, the waves.
  void order_shock_propagation(bool waves);
  /// Groups the supports by the body they hold up, bodies by height (order_, group_start_);
  /// returns the number of groups.
  std::size_t order_supports_by_height();
  /// Group gi of order_: the supports of one body.
  std::span<const SupportEntry> group(std::size_t gi) const;
  /// Each group's wave and its turns at the bodies it touches; returns the last wave.
  std::uint32_t number_waves(std::size_t groups);
  /// The groups wave by wave into wave_order_, each wave's start in wave_start_.
  void order_groups_by_wave(std::size_t groups, std::uint32_t last);
  /// Shock propagation wave by wave on the pool, with `beside` as the first phase.
  void push_up_in_waves(std::span<Contact> contacts, const Vec3& up, double dt,
                        WorkerPool& pool, BesideJob beside, std::uint32_t last);
  /// Shock propagation of one support contact: its lower body held fixed.
  void push_up(Contact& c, const Vec3& up, double dt);
  /// Shock propagation of one body on all its supports (`group` of contacts) at once.
  void push_up_body(std::span<Contact> contacts,
                    std::span<const SupportEntry> group, const Vec3& up,
                    double dt);
  /// The body a support contact holds up (the one the normal, oriented up, points into).
  static std::uint32_t upper_of(const Contact& c, const Vec3& up) {
    return c.normal.dot(up) > 0.0 ? c.b : c.a;
  }
  /// K = D S Dᵀ, K_ij = n·(change of the relative normal velocity at point i per unit impulse
  /// at j), 1/kg; a or b null: that body is held fixed.
  static NormalSystem normal_system_of(const Contact& c, const SolverBody* a,
                                       const SolverBody* b);
  /// Applies the accumulated impulses of rows slot `slot` to its bodies.
  void warm_start(std::size_t slot);
  /// One sequential-impulse sweep of rows slot `slot`: patch friction, then the normal block.
  void solve_velocity(std::size_t slot);
  /// One split-impulse sweep of rows slot `slot` on the pseudo velocities.
  void solve_position(std::size_t slot);
  /// The solver body at solver index k, or the fixed stand-in for the floor (k < 0).
  SolverBody& at(std::int32_t k) { return k < 0 ? fixed_ : sb_[k]; }
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
  /// Normal pseudo speed the split impulse drives a point to: a gap may close within the step
  /// but no more (a touching point may not be pushed deeper by the correction of another
  /// contact, a box pressed into the floor by the one above it), and a penetration beyond the
  /// slop shrinks by the position gain, m/s.
  static double split_target_of(const ContactPoint& p, double dt, const SolverSettings& s) {
    return p.separation > 0.0 ? -p.separation / dt
                              : s.position_gain * std::max(-p.separation - s.slop, 0.0) / dt;
  }

 private:
  std::span<Body> bodies_;
  std::span<const std::uint32_t> ids_;
  std::vector<std::int32_t>& index_;
  std::vector<SolverBody>& sb_;
  std::vector<ContactRows>& rows_;  // solver rows of each contact
  std::vector<ContactPointRows>& point_rows_;  // its points' rows
  std::vector<ContactImpulses>& impulses_;  // their impulses during the velocity passes
  SolverBody& fixed_;               // the floor: absorbs impulses without moving
  std::vector<SupportEntry>& supports_;  // shock propagation's entry of each contact
  std::vector<std::uint32_t>& support_start_;  // its buckets, one per solver body
  std::vector<std::pair<double, std::uint32_t>>& support_keys_;  // (height, body) to sort
  std::vector<SupportEntry>& order_;
  std::vector<std::uint32_t>& waves_;       // latest shock-propagation wave of each body
  std::vector<std::uint32_t>& wave_of_;     // wave of each group
  std::vector<std::uint32_t>& wave_start_;  // start of each wave in wave_order_
  std::vector<std::uint32_t>& wave_order_;  // solves (groups), wave by wave
  std::vector<std::uint32_t>& touches_;     // solves so far that touch each body
  std::vector<std::uint32_t>& turn_base_;   // turns each body took earlier in the solve
  std::vector<std::uint32_t>& upper_turn_;  // each solve's turn at its upper body
  std::vector<std::uint32_t>& group_start_;  // start of each body's supports in order_
  struct ShockPlan {
    bool ready = false;          // shock propagation's order is found
    std::size_t groups = 0;      // bodies held up (groups of order_)
    std::uint32_t last_wave = 0; // its last wave (several threads)
  } shock_plan_;
};

}  // namespace tumble
