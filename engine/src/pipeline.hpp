#pragma once
/// The stages of World::step and the data they share. Every stage is a free function of one
/// signature, `void stage(StepContext&)`, in a file of its own (MuJoCo's mj_step and Box2D's
/// b2World_Step as models):
///
///   broad_phase   → broad_phase.cpp   pairs of bodies whose swept boxes overlap (the sweep:
///                                     sweep_and_prune.cpp)
///   narrow_phase  → narrow_phase.cpp  box–box manifolds; box–floor manifolds of bodies in them
///   islands       → islands.cpp       bodies linked by contacts; a lone body is an island of one
///   contact_solve → contact_solve.cpp  impacts, friction, non-penetration of the islands (the
///                                     passes: contact_passes.cpp; the solver's work per
///                                     contact: contact_solver.cpp, contact_rows.cpp,
///                                     shock_propagation.cpp)
///   flight        → flight.cpp        every awake body moved over dt; a lone body's finalize
///                                     and sleep rules applied at once (finalize_body,
///                                     settle_lone_body), while it is in cache
///   finalize      → finalize.cpp      finiteness (freeze) and re-orthonormalisation
///   update_sleep  → sleep.cpp         one rule: an island still for long enough sleeps
///
/// That list is one pass; World::step runs one pass, or with WorldDef::max_overlap as many as
/// keep the bound (world_step.cpp, overlap_bound.cpp).
///
/// The World's owner thread runs the stages; a stage may share independent work (bodies,
/// pairs, contacts of one colour) among the threads of ctx.pool, each index writing only its
/// own outputs, so results are bit-identical for any number of threads.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "box_box.hpp"
#include "broad_phase.hpp"
#include "contact_solver.hpp"
#include "integrators.hpp"
#include "islands.hpp"
#include "manifold_record.hpp"
#include "tumble/body.hpp"
#include "tumble/scene.hpp"
#include "tumble/step_stats.hpp"
#include "worker_pool.hpp"

namespace tumble {

/// Where a body was when its still time began (sleep.cpp), in float: the sleep rule compares
/// displacements of millimetres, far above float's rounding of a position.
struct SleepAnchor {
  Eigen::Vector3f x = Eigen::Vector3f::Zero();  ///< Centre of mass, world, m.
  Eigen::Matrix3f R = Eigen::Matrix3f::Zero();  ///< Orientation (body → world).
};

/// What persists between steps and decides results: copied with the World, and by copy_cache
/// (pass_snapshot.hpp) for a pass taken again.
struct ContactCache {
  /// Ring of each sleeping island: sleep_next[i] is the next member (i itself when alone).
  std::vector<std::uint32_t> sleep_next;
  /// Per body, its pose when its still time began.
  std::vector<SleepAnchor> anchors;
  /// Last step's contacts, for warm starting.
  std::vector<Contact> previous;
  /// (pair key, index into previous), sorted by key.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> previous_keys;
  /// Box–box manifolds in their bodies' frames, reused while a pair barely moves
  /// (manifold_record.hpp): each record's pair, sorted, and the records in that order.
  std::vector<BodyPair> record_pairs;
  std::vector<ManifoldRecord> records;
  /// Counts changes of any body's activity (wake, sleep, freeze): caches derived from the
  /// activity flags are valid while it stays put.
  std::uint64_t activity_epoch = 0;
};

/// Broad-phase acceleration kept between steps. It never changes a result (the pairs come out
/// sorted whatever the cache held), so a World's copy starts without it.
struct BroadPhaseCache {
  std::uint64_t epoch = ~0ull;           ///< ContactCache::activity_epoch of the flags below.
  std::vector<std::uint32_t> awake;      ///< Awake bodies, ascending.
  std::vector<std::uint8_t> active;      ///< Body is awake.
  std::vector<std::uint8_t> candidate;   ///< Body may touch anything (finite, not frozen).
  SweepScratch sweep;                    ///< Sweep-and-prune orders.
  std::vector<Aabb> boxes;               ///< Each body's swept box this step.
  std::vector<std::uint8_t> box_cached;  ///< boxes[i] is a sleeping body's, still valid.
  std::vector<Aabb> fat;                 ///< Boxes the cached pairs were found for.
  std::vector<BodyPair> fat_pairs;       ///< Pairs of overlapping fat boxes (the last sweep's).
  /// Pairs found for bodies woken or escaped since the last sweep (add_woken_pairs), sorted,
  /// none of them in fat_pairs; the two lists hold the pairs that can touch.
  std::vector<BodyPair> added_pairs;
  bool fat_valid = false;                ///< fat_pairs and added_pairs hold every pair that
                                         ///< can touch, but those of the bodies in `woken`.
  std::vector<std::uint32_t> woken;      ///< Bodies woken, or out of their fat box, since
                                         ///< fat_pairs was found.
  std::vector<std::uint8_t> unpaired;    ///< Body is in `woken` (its fat box is stale).
  std::vector<std::uint8_t> escaped;     ///< Awake body left its fat box this step.
  std::size_t swept_pairs = 0;           ///< fat_pairs' size after the last sweep.
  bool fat_complete = true;              ///< fat_pairs holds every pair (within the budget).
  std::vector<QuietBound> quiet;         ///< When an unpaired body is still inside its fat box.
  /// Body i is within quiet[i]: kept for every awake body whenever its state or its bound
  /// changes (note_moved), so the next broad phase reads a byte, not the body.
  std::vector<std::uint8_t> inside;
  std::vector<std::uint8_t> stale;       ///< boxes[i] not recomputed this step (quiet body).
  std::vector<std::uint8_t> paired;      ///< Body is in fat_pairs or added_pairs.
  /// Body had no fat pair after the last sweep: its next fat box may reach down to the floor
  /// and up to where its energy can lift it (fat_box).
  std::vector<std::uint8_t> alone;
  std::vector<std::uint32_t> refit;      ///< Bodies whose fat box changed since the last sweep.
  std::vector<std::uint8_t> in_refit;    ///< Body is in `refit`.
  std::vector<std::uint32_t> near;       ///< Scratch: the bodies one query found.
  double quiet_dt = 0.0;                 ///< Step the quiet bounds were found for, s.
  Vec3 quiet_gravity = Vec3::Zero();     ///< Gravity they were found for, m/s².
};

/// A body's velocities, m/s and rad/s.
struct BodyVelocity {
  Vec3 v;
  Vec3 w;
};

/// Buffers of one step, reused between steps so that a step allocates nothing once warm.
/// Holds no result: a World's copy starts with empty scratch.
struct StepScratch {
  std::vector<BodyPair> pairs;          ///< Broad-phase pairs (sorted).
  std::vector<Contact> contacts;        ///< Floor contacts of island bodies, then box–box.
  std::vector<BoxManifold> manifolds;   ///< Manifold of each pair with points (slot ≥ 0).
  std::vector<BodyVelocity> velocities; ///< Awake bodies' velocities (narrow phase, by body).
  std::vector<Contact> floor_slots;     ///< Floor contact of each linked body (count 0: none).
  std::vector<std::int32_t> slot;       ///< Position of each pair's box–box contact, or −1.
  std::vector<std::int32_t> floor_slot; ///< Position of each linked body's floor contact, or −1.
  /// Per pair: the index of the record its manifold came from (ContactCache::records), or −1
  /// for a new manifold.
  std::vector<std::int32_t> record_from;
  std::vector<std::int32_t> record_slot;  ///< Position of each pair's next record, or −1.
  std::vector<BodyPair> next_record_pairs;    ///< The records being built (swapped into the cache).
  std::vector<ManifoldRecord> next_records;
  std::vector<std::uint32_t> slot_counts;  ///< Marked slots per range (number_slots).
  std::vector<std::uint32_t> linked;    ///< Bodies in box–box contacts, ascending.
  std::vector<std::uint8_t> marked;     ///< Scratch of `linked`: body is in a box–box contact.
  std::vector<BodyPair> links;          ///< Body pairs of the box–box contacts.
  std::vector<std::uint8_t> wakes;      ///< 1 where a link's body was asleep when found.
  std::vector<double> speed;            ///< Point-speed bound of each linked body, m/s.
  std::vector<double> reach;            ///< Fastest neighbour of each body, m/s.
  int woken = 0;                        ///< Sleeping bodies the narrow phase woke.
  /// The pairs, manifolds and slots of the step's last detection round that woke a body (the
  /// next round reuses their answers: nothing has moved since), and that step's index.
  std::vector<BodyPair> earlier_pairs;
  std::vector<BoxManifold> earlier_manifolds;
  std::vector<std::int32_t> earlier_slot;
  std::uint64_t earlier_step = ~std::uint64_t{0};
  IslandScratch island;                 ///< Union–find and island lists.
  std::vector<std::uint32_t> solver_bodies;  ///< Bodies in islands of two or more, ascending.
  std::vector<std::uint32_t> lone_bodies;    ///< Awake bodies touching no other body.
  std::vector<BodyState> before;             ///< State of solver_bodies[k] at the step start.
  SolverScratch solver;                      ///< The contact solver's per-body data.
  std::vector<SpinCache> spins;              ///< The turn of lone_bodies[k] in flight (a cube's).
};

/// Everything a stage reads and writes.
struct StepContext {
  const WorldDef& world;     ///< Settings (gravity, floor, integrator, TOI method).
  double dt;                 ///< Step, s.
  std::uint64_t step_index;  ///< Steps taken before this one.
  std::span<Body> bodies;    ///< All bodies, by BodyId.
  ContactCache& cache;       ///< Persistent contact and sleep data.
  BroadPhaseCache& broad;    ///< Broad-phase acceleration.
  StepScratch& scratch;      ///< This step's buffers.
  StepStats& stats;          ///< This step's counters.
  WorkerPool& pool;          ///< Threads for the stages' independent work (1: inline).
  bool timed = false;        ///< The World times its stages (and the contact solve's passes).
  bool unequal_moments = true;  ///< Some body is not a cube (flight may turn bodies in lanes).
};

/// Sizes the cache for `body_count` bodies, each alone (not in a sleeping island); called
/// again with a larger count when a body is added.
void init_caches(ContactCache& cache, std::size_t body_count);

/// Stage: swept boxes of the candidates and the pairs whose boxes overlap (scratch.pairs).
void broad_phase(StepContext& ctx);
/// Stage: box–box manifolds of the pairs that touch within the step (scratch.contacts),
/// waking the sleeping islands they reach (scratch.woken counts them), and the floor
/// manifolds of the bodies in those contacts.
void narrow_phase(StepContext& ctx);
/// Stage: islands of touching bodies (scratch.solver_bodies); every other awake body is an
/// island of one (scratch.lone_bodies); the island bodies' start states kept for finalize
/// (scratch.before).
void islands(StepContext& ctx);
/// Stage: impulses of the islands' contacts; leaves the islands' momenta at the end of the
/// step and their split-impulse pseudo velocities in scratch.solver.
void contact_solve(StepContext& ctx);
/// Stage: moves every awake body over dt: a lone body with the scene's integrator and its
/// floor impacts at their time of impact, then finalize_body and settle_lone_body on it; an
/// island body with its solved velocities.
void flight(StepContext& ctx);
/// Stage: finalize_body on every island body.
void finalize(StepContext& ctx);
/// Stage: one sleep rule for every island (a lone body took it in flight: settle_lone_body).
void update_sleep(StepContext& ctx);

/// Whether the step after `step_index` steps re-orthonormalises R (every kGramSchmidtInterval).
bool renormalize_after(std::uint64_t step_index);
/// Finalize's rule for one stepped body: non-finite, it gets `before` back and is frozen
/// (returns false; the caller counts it in StepStats::newly_frozen); else its R is
/// re-orthonormalised when `renormalize`. Touches only b.
bool finalize_body(Body& b, const BodyState& before, bool renormalize);
/// The sleep rule for lone body `id` (an island of one) after its finalize: its still time,
/// and asleep at rest once still for long enough (returns true; the caller moves
/// ContactCache::activity_epoch). Touches only b and cache's slots of id: safe across threads
/// for distinct bodies.
bool settle_lone_body(Body& b, std::uint32_t id, ContactCache& cache, double dt,
                      const WorldDef& world);

/// Body i's state changed (flight, an impulse): whether it is still within its quiet bound,
/// for the next broad phase (BroadPhaseCache::inside). Writes only slot i: safe across threads
/// for distinct bodies.
inline void note_moved(BroadPhaseCache& k, std::uint32_t i, const BodyState& s) {
  if (i < k.inside.size()) k.inside[i] = within(k.quiet[i], s);
}

/// A new quiet bound for body i, in flight and out of its last one, from its fat box, where it
/// has no cached pair (broad_phase.cpp). Thread-safe for distinct i.
void renew_quiet(StepContext& ctx, std::uint32_t i, const Body& b);

/// note_moved for lone body i after its flight: a body in flight that outlived its quiet
/// bound takes a new one (renew_quiet). Thread-safe for distinct i.
inline void note_flown(StepContext& ctx, std::uint32_t i, const Body& b) {
  BroadPhaseCache& k = ctx.broad;
  if (i >= k.inside.size()) return;
  k.inside[i] = within(k.quiet[i], b.s);
  if (!k.inside[i] && !b.in_contact && k.quiet[i].p2 >= 0.0) renew_quiet(ctx, i, b);
}

/// Pairs of bodies whose boxes overlap as placed (stops counting just past pair_budget).
std::size_t initial_pairs(std::span<const Body> bodies, const Vec3& gravity);

/// Wakes body id and every body of its sleeping island.
void wake_island(ContactCache& cache, std::span<Body> bodies, std::uint32_t id);

}  // namespace tumble
