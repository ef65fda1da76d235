#pragma once
/// Contacts between bodies (and between those bodies and the floor) and the solver of the
/// bodies touching each other: exact impact impulses, then sequential impulses with warm
/// starting and Coulomb friction, then split-impulse position correction.
/// Pure functions over the caller's buffers; thread-safe.
#include <array>
#include <chrono>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "active_set.hpp"
#include "contact_colours.hpp"
#include "tumble/body.hpp"
#include "tumble/step_stats.hpp"

namespace tumble {

/// Stands for the floor (a static body) in Contact::a.
inline constexpr std::uint32_t kStaticBody = 0xFFFFFFFFu;
/// Most points of one contact: 4 for box–box, up to 8 box vertices on the floor.
inline constexpr int kMaxContactPoints = 8;

/// One point of a contact, with the normal impulse it accumulated (kept for warm starting).
struct ContactPoint {
  Vec3 position = Vec3::Zero();  ///< World, m.
  double separation = 0.0;       ///< Gap along the normal at the start of the step, m.
  std::uint32_t id = 0;          ///< Feature id (persistent between steps).
  double normal_impulse = 0.0;   ///< Accumulated normal impulse, N·s (≥ 0).
  // Per-step solver data.
  Vec3 ra = Vec3::Zero(), rb = Vec3::Zero();  ///< Offsets from the centres of mass, m.
};

/// The contact of body a (or the floor, a = kStaticBody) with body b: normal from a to b.
struct Contact {
  std::uint32_t a = kStaticBody;  ///< Body index, or kStaticBody for the floor.
  std::uint32_t b = 0;            ///< Body index.
  Vec3 normal = Vec3::UnitY();    ///< Unit, world, from a to b.
  double friction = 0.0;          ///< Coulomb μ of the pair.
  double restitution = 0.0;       ///< e of the pair (applied to impacts only).
  int count = 0;                  ///< Points in use.
  /// Accumulated patch friction (kept for warm starting): along t1 and t2 at the patch's
  /// centre of pressure, N·s, and the twist about the normal, N·m·s.
  std::array<double, 3> friction_impulse{};
  std::array<ContactPoint, kMaxContactPoints> points{};
};

/// Tuning of the contact solver.
struct SolverSettings {
  int velocity_iterations = 10;     ///< Sequential-impulse sweeps.
  int position_iterations = 4;      ///< Split-impulse sweeps.
  /// The first of several sweeps runs backward (top of the stacks first), the rest in contact
  /// order (floor contacts first): see `sweep` in contact_passes.cpp.
  bool first_sweep_backward = true;
  double slop = 2e-4;               ///< Penetration left alone, m.
  double position_gain = 0.4;       ///< Fraction of the penetration beyond slop removed per step.
  bool shock_propagation = true;    ///< Final ground-up sweep with lower bodies held fixed.
};

/// Speculative distance: points closer than this (plus the distance the bodies can close in
/// a step) are kept as contacts, m.
inline constexpr double kSpeculativeDistance = 0.02;

/// The floor contact of a body: every vertex closer to the plane y = floor_y than `margin`
/// (m), normal +y. Returns the number of points.
int floor_contact(const BodyState& s, const BodyConstants& c, std::uint32_t body,
                  double floor_y, double margin, Contact& out);

/// Copies the accumulated impulses of points with the same feature id, and the patch friction,
/// from `previous`.
void warm_start_from(Contact& contact, const Contact& previous);

/// Velocities of a body during the solve (I⁻¹ fixed at the start of the step). What a
/// velocity sweep reads and writes of it (v, w, inv_mass, turn) fills its first 64-byte line,
/// and no two bodies share a line: on several threads a contact then moves one line per body
/// between cores (the turn that lets it start brings the velocities with it), and a thread
/// writing one body never evicts a neighbour the other thread holds. Laid out one after
/// another at 176 bytes, with the turns in an array of their own, `pile`'s contact solve took
/// 10 % longer on two threads.
struct alignas(64) SolverBody {
  Vec3 v = Vec3::Zero();            ///< m/s.
  Vec3 w = Vec3::Zero();            ///< rad/s.
  double inv_mass = 0.0;            ///< 1/kg.
  /// Contacts of this body a coloured sweep has taken (Solver's sweeps; atomic_ref only).
  std::uint32_t turn = 0;
  Vec3 vp = Vec3::Zero();           ///< Split-impulse pseudo velocity, m/s.
  Vec3 wp = Vec3::Zero();           ///< Split-impulse pseudo angular velocity, rad/s.
  Mat3 inv_inertia = Mat3::Zero();  ///< World I⁻¹ at the step start, 1/(kg·m²).
};

/// One contact point's row along the normal, computed once a step so that the iterations are
/// dot products and axpys (Box2D's contact solver).
struct PointRows {
  Vec3 ang_a;          ///< ra × n, m (zero for the floor).
  Vec3 ang_b;          ///< rb × n, m.
  Vec3 inv_a;          ///< I_a⁻¹ (ra × n), 1/(kg·m).
  Vec3 inv_b;          ///< I_b⁻¹ (rb × n), 1/(kg·m).
  double normal_mass;  ///< 1 / (n·K n), kg.
  double target;       ///< Normal speed the point must reach (Solver::target_of), m/s.
  double split_target; ///< Normal pseudo speed the split impulse drives the point to, m/s.
};

/// A contact's three friction rows: t1 and t2 at the patch's centre of pressure, the twist
/// about n (whose angular rows are n itself, ContactRows::dir[0]).
struct FrictionRows {
  std::array<double, 3> mass{};      ///< 1 / (d·K d) of each row, kg (twist: kg·m²).
  double radius = 0.0;               ///< Mean distance of the points from that centre, m.
  std::array<Vec3, 2> ang_a, ang_b;  ///< r0 × t1, r0 × t2 of each body, m.
  std::array<Vec3, 3> inv_a, inv_b;  ///< I⁻¹ times those and n, 1/(kg·m) (twist: 1/(kg·m²)).
};

/// A contact's solver data: its directions, its normal block in the patch's plane coordinates
/// and its friction rows. K⁺ = D P Dᵀ (active_set.hpp); the normal velocities of all points
/// are vn = D y with y = (normal speed at the patch origin, the two tipping rates), and an
/// impulse Δλ = D z moves the bodies by the patch wrench u = G z, G = DᵀD: a block iteration
/// works on 3-vectors whatever the number of points.
///
/// The velocity and position passes read the rows and write the contact's ContactImpulses
/// alone, not the Contact: the rows hold the contact's bodies, and the impulses its points'
/// accumulated normal impulses and its patch friction while the passes run
/// (Solver::store_impulses puts them back) and its split impulses. Both lie in the order the
/// passes meet them (colour by colour on several threads), so each thread streams through
/// memory instead of gathering ~1 KB contacts from all over the list.
///
/// The rows hold what a velocity sweep reads, in the order it reads it (992 bytes), and the
/// points' rows (PointRows), which only the split impulse, the warm start, the collision
/// pass's test and a block that would pull read, lie in an array of their own
/// (SolverScratch::point_rows): with them inside, a contact's rows were 2,048 bytes, of which
/// a four-point sweep read under half.
struct ContactRows {
  std::int32_t a = -1, b = -1;  ///< Solver index of each body (−1: the floor).
  int count = 0;                ///< Points in use.
  double mu = 0.0;              ///< Coulomb μ of the pair (Contact::friction).
  std::array<Vec3, 3> dir;      ///< n, t1, t2 (unit, world).
  FrictionRows friction;        ///< The patch's friction rows.
  /// Columns of C of body a: (r0 × n, t1 × n, t2 × n), m; b's last two are the same.
  std::array<Vec3, 3> ca;
  Vec3 cb0 = Vec3::Zero();      ///< First column of C of body b, r0 × n, m.
  Vec3 Pt = Vec3::Zero();       ///< P Dᵀ (the points' target normal speeds), N·s.
  Mat3 PG = Mat3::Zero();       ///< P G, 1/kg.
  Mat3 G = Mat3::Zero();        ///< DᵀD.
  std::array<Vec3, 3> inv_ca, inv_cb;  ///< I⁻¹ times the columns of a and of b, 1/(kg·m).
  PlaneCoordinates D;  ///< (1, α, β) of each point; last: a sweep reads its first `count` rows.
};

/// The rows of each point of one contact (PointRows), count of them in use.
using ContactPointRows = std::array<PointRows, kMaxContactPoints>;

/// A contact's accumulated impulses during the velocity passes (Contact's, copied in and out)
/// and the split impulse's, which live for the step only.
struct ContactImpulses {
  std::array<double, kMaxContactPoints> normal{};  ///< Each point's normal impulse, N·s.
  std::array<double, 3> friction{};                ///< Contact::friction_impulse.
  std::array<double, kMaxContactPoints> pseudo{};  ///< Each point's split impulse, N·s.
};

/// One support contact in shock propagation's order: the height of the body it holds up (m,
/// along −gravity), that body, and the contact's index.
struct SupportEntry {
  double height;
  std::uint32_t upper;
  std::uint32_t contact;
  /// On several threads: the solver index of the body under it (−1: the floor) and how many
  /// earlier solves touch that body (its turn, SolverBody::turn).
  std::int32_t lower = -1;
  std::uint32_t lower_turn = 0;
};

/// The solver's buffers, reused between steps.
struct SolverScratch {
  std::vector<SolverBody> bodies;     ///< One per solver body, in the order given.
  std::vector<std::int32_t> index;    ///< Body id → position in `bodies`, −1 when absent.
  std::vector<ContactRows> rows;      ///< Solver rows of each contact, in sweep order.
  std::vector<ContactPointRows> point_rows;  ///< Its points' rows, in the same order.
  std::vector<ContactImpulses> impulses;  ///< Impulses of each contact, in sweep order.
  SolverBody fixed;                   ///< Stands for the floor: zero inverse mass and inertia.
  std::vector<SupportEntry> supports; ///< Shock propagation's entry of each contact.
  std::vector<std::uint32_t> support_start;  ///< Its buckets of entries, one per body.
  std::vector<std::pair<double, std::uint32_t>> support_keys;  ///< (height, body) to sort.
  std::vector<SupportEntry> order;    ///< Shock propagation order.
  std::vector<std::uint32_t> waves, wave_of, wave_start, wave_order;  ///< Its waves.
  std::vector<std::uint32_t> touches;     ///< Its solves so far that touch each solver body.
  std::vector<std::uint32_t> upper_turn;  ///< Each solve's turn at the body it holds up.
  std::vector<std::uint32_t> group_start;  ///< Its solves: each body's supports in `order`.
  std::vector<std::int32_t> colour_a, colour_b;  ///< Solver index of each contact's bodies.
  std::vector<std::uint32_t> slot_of;  ///< Each contact's rows slot (the inverse of colour order).
  /// Each solver body's turns taken so far in this solve (SolverBody::turn is zeroed once, in
  /// parallel, when the solve starts): a sweep or shock propagation waits for turns counted
  /// from there.
  std::vector<std::uint32_t> turn_base;
  ContactColours colours;                        ///< The contacts grouped by colour.
};

class WorkerPool;

/// Charges the wall time between laps to the contact solve's passes (StepStats::solve_pass_ns)
/// when the World times its stages; otherwise reads no clock. The owner's thread only.
class PassClock {
 public:
  /// Adds into `ns` (kSolvePassCount counters, by SolvePass); null: times nothing.
  explicit PassClock(std::uint64_t* ns) : ns_(ns) {
    if (ns_) last_ = std::chrono::steady_clock::now();
  }
  /// Adds the time since the last lap (or since construction) to `pass`.
  void lap(SolvePass pass) {
    if (!ns_) return;
    const auto now = std::chrono::steady_clock::now();
    ns_[static_cast<int>(pass)] += static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::nanoseconds>(now - last_).count());
    last_ = now;
  }

 private:
  std::uint64_t* ns_;
  std::chrono::steady_clock::time_point last_{};
};

/// Solves the velocities of `bodies[solver_bodies]` over dt under gravity with the contacts:
/// impacts (relative normal speed above the restitution threshold) get an exact simultaneous
/// impulse per contact with restitution e; then sequential impulses with warm starting and
/// friction keep resting contacts from approaching; a split-impulse pass finds the pseudo
/// velocities that remove deep penetration. Writes the bodies' end-of-step momenta P, L (their
/// positions are flight's job) and leaves v, w, vp, wp in scratch.bodies. Returns the number
/// of impacts. Contacts of one colour (contact_colours.hpp) are solved at the same time on the
/// threads of `pool`; the result does not depend on their number. Each pass's time goes to
/// `clock`.
int solve_contacts(std::span<Body> bodies, std::span<const std::uint32_t> solver_bodies,
                   std::span<Contact> contacts, const Vec3& gravity, double dt,
                   const SolverSettings& settings, SolverScratch& scratch, WorkerPool& pool,
                   PassClock& clock);

}  // namespace tumble
