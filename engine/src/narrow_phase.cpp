#include <algorithm>
#include <atomic>
#include <cmath>
#include <span>
#include <utility>

#include "box_box.hpp"
#include "pipeline.hpp"

namespace tumble {
namespace {

// A body pair joins the contact solve only when a point of its manifold is closer than this
// (m) or will close its gap within the step at the current velocities. Pairs that merely pass
// near each other keep the lone path with the scene's exact integrator.
constexpr double kTouchDistance = 1e-3;

using Motion = BodyVelocity;

Motion motion_of(const Body& b) { return {b.s.P * b.c.inv_mass, angular_velocity(b.s, b.c)}; }

/// Body i's velocities: those found for the step when `shared` and i is awake, else afresh.
Motion motion(const StepContext& ctx, std::uint32_t i, bool shared) {
  return shared && ctx.broad.active[i] ? ctx.scratch.velocities[i] : motion_of(ctx.bodies[i]);
}

/// True when some point of the manifold touches or will touch within dt.
bool touches(const BoxManifold& m, const Body& a, const Motion& ma, const Body& b,
             const Motion& mb, double dt) {
  for (int i = 0; i < m.count; ++i) {
    const Vec3& p = m.points[i].position;
    const double vn =
        (mb.v + mb.w.cross(p - b.s.x) - ma.v - ma.w.cross(p - a.s.x)).dot(m.normal);
    if (m.points[i].separation + std::min(vn, 0.0) * dt <= kTouchDistance) return true;
  }
  return false;
}

/// A separation (m) past which no point of a manifold kept within `margin` passes touches():
/// such a point lies within half its separation of both boxes' surfaces, so its normal speed
/// is at most |v_a − v_b| + |ω_a| (r_a + margin / 2) + |ω_b| (r_b + margin / 2), which over dt
/// is `closing` and the margin's part. collide_boxes then skips the faces' clipping.
/// `spins`: |ω_a| + |ω_b|, rad/s.
double touch_limit(double spins, double closing, double margin, double dt) {
  constexpr double kRoundOff = 1e-9;  // m: far above the clipping's rounding
  return kTouchDistance + closing + 0.5 * margin * dt * spins + kRoundOff;
}

/// Writes the contact of manifold m between bodies a and b into c (its points past m.count
/// are left as they were: nothing reads them).
void write_contact(const BoxManifold& m, std::uint32_t a, std::uint32_t b, const Body& ba,
                   const Body& bb, Contact& c) {
  c.a = a;
  c.b = b;
  c.normal = m.normal;
  c.friction = std::sqrt(ba.c.friction * bb.c.friction);
  c.restitution = std::max(ba.c.restitution, bb.c.restitution);
  c.count = m.count;
  c.friction_impulse = {};
  for (int i = 0; i < m.count; ++i) {
    ContactPoint& p = c.points[i];
    p = ContactPoint{};
    p.position = m.points[i].position;
    p.separation = m.points[i].separation;
    p.id = m.points[i].id;
  }
}

/// The manifold of pair p, or none (count 0) when its boxes will not touch within the step.
/// `recordable` is set when the boxes move less than kRecycleDistance a step (the manifold is
/// worth keeping for the next: manifold_record.hpp).
BoxManifold manifold_of(const StepContext& ctx, const BodyPair& p, bool shared,
                        bool& recordable) {
  const Body& a = ctx.bodies[p.first];
  const Body& b = ctx.bodies[p.second];
  const Motion ma = motion(ctx, p.first, shared), mb = motion(ctx, p.second, shared);
  const double spin_a = ma.w.norm(), spin_b = mb.w.norm();
  const double closing = ctx.dt * ((ma.v - mb.v).norm() + spin_a * a.c.bounding_radius +
                                   spin_b * b.c.bounding_radius);
  recordable = closing < kRecycleDistance;
  // Bounding spheres farther apart than the margin: the boxes are too, and stay more than the
  // speculative distance apart over the step, so nothing the full test could keep touches.
  // In `pile`'s first 45 steps (its fall) 58 % of the pairs end here, each for a separating-
  // axis test.
  const double margin = kSpeculativeDistance + closing;
  const double reach = a.c.bounding_radius + b.c.bounding_radius + margin;
  if ((b.s.x - a.s.x).squaredNorm() > reach * reach) return {};
  BoxManifold m = collide_boxes(a.s, a.c, b.s, b.c, margin,
                                touch_limit(spin_a + spin_b, closing, margin, ctx.dt));
  if (m.count > 0 && !touches(m, a, ma, b, mb, ctx.dt)) m.count = 0;
  return m;
}

/// Pair p's manifold from `record` into `out` while its boxes are still close to the record's
/// pose (false: not recycled, `out` untouched), its count 0 when they will not touch within
/// the step.
bool recycled(const StepContext& ctx, const BodyPair& p, bool shared,
              const ManifoldRecord& record, BoxManifold& out) {
  const Body& a = ctx.bodies[p.first];
  const Body& b = ctx.bodies[p.second];
  if (!recycle_manifold(record, a.s, a.c.bounding_radius, b.s, b.c.bounding_radius, out))
    return false;
  const Motion ma = motion(ctx, p.first, shared), mb = motion(ctx, p.second, shared);
  if (!touches(out, a, ma, b, mb, ctx.dt)) out.count = 0;
  return true;
}

/// Finds pairs in a sorted list by walking it with ascending pairs.
class PairWalk {
 public:
  /// Starts at the first entry of `list` not below `first`.
  PairWalk(std::span<const BodyPair> list, const BodyPair& first)
      : list_(list), at_(std::lower_bound(list.begin(), list.end(), first)) {}
  /// Index of `p` in the list, or −1; p not below the pair of the call before.
  std::int32_t find(const BodyPair& p) {
    while (at_ != list_.end() && *at_ < p) ++at_;
    return at_ != list_.end() && *at_ == p ? static_cast<std::int32_t>(at_ - list_.begin()) : -1;
  }

 private:
  std::span<const BodyPair> list_;
  std::span<const BodyPair>::iterator at_;
};

/// Numbers the marked items in order: slot[k] ≥ 0 (marked) becomes the item's position among
/// them, −1 stays; returns how many. The marks are set on the pool where each item is found:
/// read back from the items themselves (a manifold is ~350 bytes, a contact ~1 KB) this pass
/// missed the cache once per item on the owner's thread, ~0.1 ms a step in `pile`. The marks
/// are numbered on the pool too, in fixed ranges (each range's marks counted, the counts
/// summed in range order, then each range numbered from its sum): read on the owner's thread
/// alone, the marks the other threads had just written came over one cache line at a time,
/// ~40 µs of `pile`'s step on two threads while the others waited.
std::uint32_t number_slots(std::vector<std::int32_t>& slot, std::vector<std::uint32_t>& counts,
                           WorkerPool& pool) {
  constexpr std::size_t kRange = 1024;  // marks per range
  const std::size_t n = slot.size();
  counts.resize((n + kRange - 1) / kRange);
  // Each range counts into a local and writes its count once: neighbouring counts share a
  // cache line between the threads.
  pool.for_each(counts.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t r = begin; r < end; ++r) {
      std::uint32_t marked = 0;
      for (std::size_t k = r * kRange, last = std::min(n, k + kRange); k < last; ++k)
        marked += slot[k] >= 0 ? 1 : 0;
      counts[r] = marked;
    }
  });
  std::uint32_t total = 0;
  for (std::uint32_t& c : counts) total += std::exchange(c, total);
  pool.for_each(counts.size(), 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t r = begin; r < end; ++r) {
      auto next = static_cast<std::int32_t>(counts[r]);
      for (std::size_t k = r * kRange, last = std::min(n, k + kRange); k < last; ++k)
        slot[k] = slot[k] >= 0 ? next++ : -1;
    }
  });
  return total;
}

/// The next step's records (ContactCache::records), in pair order: each pair with a manifold
/// keeps the record it came from, or records its new one when its boxes move slowly
/// (record_slot marks both, record_from says which).
void keep_records(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  const std::uint32_t count = number_slots(s.record_slot, s.slot_counts, ctx.pool);
  s.next_record_pairs.resize(count);
  s.next_records.resize(count);
  ctx.pool.for_each(s.pairs.size(), 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::int32_t r = s.record_slot[k];
      if (r < 0) continue;
      const BodyPair& p = s.pairs[k];
      s.next_record_pairs[r] = p;
      s.next_records[r] = s.record_from[k] >= 0
                              ? ctx.cache.records[s.record_from[k]]
                              : record_manifold(s.manifolds[k], ctx.bodies[p.first].s,
                                                ctx.bodies[p.second].s);
    }
  });
  std::swap(ctx.cache.record_pairs, s.next_record_pairs);
  std::swap(ctx.cache.records, s.next_records);
}

/// The bodies of the box–box contacts, ascending, each once. With many contacts, by marking
/// them and reading the marks in body order (a sort of both ends of every link was 1.5 % of
/// `pile`, all on one thread); with a few among many bodies, by sorting those few.
void list_linked(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  s.linked.clear();
  const std::size_t n = ctx.bodies.size();
  if (16 * s.links.size() >= n) {
    s.marked.assign(n, 0);
    for (const BodyPair& p : s.links) s.marked[p.first] = s.marked[p.second] = 1;
    for (std::uint32_t i = 0; i < n; ++i)
      if (s.marked[i]) s.linked.push_back(i);
    return;
  }
  for (const BodyPair& p : s.links) s.linked.insert(s.linked.end(), {p.first, p.second});
  std::sort(s.linked.begin(), s.linked.end());
  s.linked.erase(std::unique(s.linked.begin(), s.linked.end()), s.linked.end());
}

/// Each awake body's velocities (ω = R I⁻¹ Rᵀ L) found once for the step, when the pairs are
/// at least half as many as the awake bodies (returns true): a pile has ~7 pairs per body,
/// each of which read both bodies' (4 % of `pile`'s instructions). 10,000 bodies in flight
/// with a few pairs find them pair by pair. The same function either way: the same bits.
bool share_velocities(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  const std::vector<std::uint32_t>& awake = ctx.broad.awake;
  if (2 * s.pairs.size() < awake.size() || s.pairs.empty()) return false;
  s.velocities.resize(ctx.bodies.size());
  ctx.pool.for_each(awake.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k)
      s.velocities[awake[k]] = motion_of(ctx.bodies[awake[k]]);
  });
  return true;
}

/// The manifolds of pairs [begin, end) into scratch (manifolds, slot, record_from,
/// record_slot): the earlier round's answer, a recycled record, or a new test, in that order.
/// A round after one that woke bodies keeps the earlier round's answer for each pair it
/// already had (narrow_phase kept its pairs; its manifolds and slots are still here): no body
/// has moved since, so a manifold found again would be the same, bit for bit. In `pile`
/// (kept awake as `tumble-bench contact` keeps it) 43 % of the steps have a second round,
/// which collided every pair again: 30 % of the box–box tests.
void collide_range(const StepContext& ctx, std::span<const BodyPair> earlier, bool shared,
                   std::size_t begin, std::size_t end) {
  StepScratch& s = ctx.scratch;
  // The lists are sorted: one search each, then walks.
  PairWalk in_earlier(earlier, s.pairs[begin]),
      in_records(ctx.cache.record_pairs, s.pairs[begin]);
  for (std::size_t k = begin; k < end; ++k) {
    const std::int32_t record = in_records.find(s.pairs[k]);
    const std::int32_t at = in_earlier.find(s.pairs[k]);
    if (at >= 0) {  // the earlier round's manifold, and the record it kept, if any
      s.slot[k] = s.earlier_slot[at] >= 0 ? 0 : -1;
      if (s.slot[k] == 0) s.manifolds[k] = s.earlier_manifolds[at];
      s.record_from[k] = record;
      s.record_slot[k] = s.slot[k] == 0 && record >= 0 ? 0 : -1;
      continue;
    }
    if (record >= 0 &&
        recycled(ctx, s.pairs[k], shared, ctx.cache.records[record], s.manifolds[k])) {
      s.slot[k] = s.record_slot[k] = s.manifolds[k].count > 0 ? 0 : -1;
      s.record_from[k] = record;
      continue;
    }
    bool recordable = false;
    const BoxManifold m = manifold_of(ctx, s.pairs[k], shared, recordable);
    s.slot[k] = m.count > 0 ? 0 : -1;
    if (m.count > 0) s.manifolds[k] = m;
    s.record_from[k] = -1;
    s.record_slot[k] = m.count > 0 && recordable ? 0 : -1;
  }
}

/// The links (pairs with a contact, in slot order), whether each wakes a sleeping body, and
/// the step's count of contact points, from the numbered slots; then the sleeping islands
/// the links reach woken, in link order.
void link_and_wake(StepContext& ctx, std::uint32_t count) {
  constexpr std::size_t kGrain = 64;
  StepScratch& s = ctx.scratch;
  s.links.resize(count);
  s.wakes.resize(count);
  ctx.stats.contact_points = 0;
  ctx.pool.for_each(s.pairs.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    std::uint32_t points = 0;
    for (std::size_t k = begin; k < end; ++k) {
      if (s.slot[k] < 0) continue;
      const BodyPair& p = s.pairs[k];
      const Body& a = ctx.bodies[p.first];
      const Body& b = ctx.bodies[p.second];
      s.links[s.slot[k]] = p;
      s.wakes[s.slot[k]] = a.activity == Activity::asleep || b.activity == Activity::asleep;
      points += static_cast<std::uint32_t>(s.manifolds[k].count);
    }
    std::atomic_ref(ctx.stats.contact_points).fetch_add(points, std::memory_order_relaxed);
  });
  // Waking only wakes: a link whose bodies were awake above needs nothing here, and the
  // others are woken in link order as before. Reading every link's two ~300-byte body
  // records again on the owner's thread missed the cache ~2,000 times a step in `pile`.
  s.woken = 0;
  for (std::size_t i = 0; i < s.links.size(); ++i) {
    if (!s.wakes[i]) continue;
    for (const std::uint32_t id : {s.links[i].first, s.links[i].second}) {
      if (ctx.bodies[id].activity != Activity::asleep) continue;
      wake_island(ctx.cache, ctx.bodies, id);
      ++s.woken;
    }
  }
}

/// Box–box manifolds of the broad-phase pairs (each pair on its own, shared among the pool's
/// threads), numbered in pair order (their contacts are written by collide_floor, behind the
/// floor's), then in pair order the sleeping islands they wake.
void collide_pairs(StepContext& ctx) {
  constexpr std::size_t kGrain = 16;  // pairs per chunk: 0.2–1 µs each
  StepScratch& s = ctx.scratch;
  const bool shared = share_velocities(ctx);
  std::span<const BodyPair> earlier;
  if (s.earlier_step == ctx.step_index) {  // a second round: the first's answers
    earlier = s.earlier_pairs;
    std::swap(s.earlier_manifolds, s.manifolds);
    std::swap(s.earlier_slot, s.slot);
  }
  // Only the manifolds with points are kept (a quarter of `pile`'s pairs).
  s.manifolds.resize(s.pairs.size());
  s.slot.resize(s.pairs.size());
  s.record_from.resize(s.pairs.size());
  s.record_slot.resize(s.pairs.size());
  std::atomic<bool> any_record = false;
  ctx.pool.for_each(s.pairs.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    collide_range(ctx, earlier, shared, begin, end);
    if (std::any_of(s.record_slot.begin() + begin, s.record_slot.begin() + end,
                    [](std::int32_t r) { return r >= 0; }))
      any_record.store(true, std::memory_order_relaxed);
  });
  const std::uint32_t count = number_slots(s.slot, s.slot_counts, ctx.pool);
  if (any_record.load(std::memory_order_relaxed)) {
    keep_records(ctx);
  } else {  // a falling pile records nothing: no pass over its pairs to say so
    ctx.cache.record_pairs.clear();
    ctx.cache.records.clear();
  }
  link_and_wake(ctx, count);
  list_linked(ctx);
}

// The floor joins the same solve as a static body, so a stack's bottom box feels both its
// load and the floor in one consistent set of impulses. Floor contacts go first: Gauss–
// Seidel then carries the support up the stack within one sweep. A body struck from above can
// be driven down faster than it moves now: its floor margin also covers the speed of the
// fastest body touching it. Every linked body's floor contact is found on its own (shared
// among the pool's threads), and those that reach the floor are copied, in ascending body
// order, ahead of the box–box contacts, which are then written from their manifolds straight
// into place (written apart and copied behind the floor's, each ~1 KB contact crossed memory
// twice more). Each linked body's speed bound is found once, on the pool: found contact by
// contact on the caller they were 2 % of `pile`'s instructions, all of them on one thread.
void collide_floor(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  std::uint32_t floor_count = 0;
  if (ctx.world.floor && !s.links.empty()) {
    s.speed.resize(ctx.bodies.size());
    s.reach.resize(ctx.bodies.size());
    ctx.pool.for_each(s.linked.size(), 256, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        const Body& b = ctx.bodies[s.linked[k]];
        s.speed[s.linked[k]] = point_speed_bound(b.s, b.c);
        s.reach[s.linked[k]] = 0.0;
      }
    });
    for (const BodyPair& p : s.links) {  // the contacts' bodies, 8 bytes a pair
      s.reach[p.first] = std::max(s.reach[p.first], s.speed[p.second]);
      s.reach[p.second] = std::max(s.reach[p.second], s.speed[p.first]);
    }
    s.floor_slots.resize(s.linked.size());
    s.floor_slot.resize(s.linked.size());
    ctx.pool.for_each(s.linked.size(), 64, [&](std::size_t begin, std::size_t end) {
      for (std::size_t k = begin; k < end; ++k) {
        const std::uint32_t id = s.linked[k];
        const Body& b = ctx.bodies[id];
        const double margin = kSpeculativeDistance + ctx.dt * (s.speed[id] + s.reach[id]);
        const int points =
            floor_contact(b.s, b.c, id, ctx.world.floor->height, margin, s.floor_slots[k]);
        s.floor_slot[k] = points > 0 ? 0 : -1;
      }
    });
    floor_count = number_slots(s.floor_slot, s.slot_counts, ctx.pool);
  }
  s.contacts.resize(floor_count + s.links.size());
  ctx.pool.for_each(s.pairs.size(), 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      if (s.slot[k] < 0) continue;
      const BodyPair& p = s.pairs[k];
      write_contact(s.manifolds[k], p.first, p.second, ctx.bodies[p.first],
                    ctx.bodies[p.second], s.contacts[floor_count + s.slot[k]]);
    }
  });
  if (floor_count == 0) return;
  ctx.pool.for_each(s.linked.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k)
      if (s.floor_slot[k] >= 0) s.contacts[s.floor_slot[k]] = s.floor_slots[k];
  });
}

}  // namespace

void narrow_phase(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  collide_pairs(ctx);
  collide_floor(ctx);  // floor contacts, then the box–box ones
  ctx.stats.contacts = static_cast<std::uint32_t>(s.links.size());
  if (s.woken > 0) {  // another round follows (World::step): it reuses this one's answers
    std::swap(s.earlier_pairs, s.pairs);  // the broad phase refills the pairs
    s.earlier_step = ctx.step_index;
  }
}

}  // namespace tumble
