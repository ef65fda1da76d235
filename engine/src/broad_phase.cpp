/// The broad-phase stage: swept and fat boxes, the cached pairs and their upkeep (the sweep
/// itself is in sweep_and_prune.cpp).
#include "broad_phase.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "pipeline.hpp"

namespace tumble {

Aabb swept_aabb(const BodyState& s, const BodyConstants& c, const Vec3& gravity, double dt,
                double margin) {
  // Half extents of the rotated box along the world axes: Σ_k |R_ik| h_k, column by column
  // (Eigen's product of the 3×3 |R| cost twice as many instructions).
  const Vec3 half = s.R.col(0).cwiseAbs() * c.half_extents.x() +
                    s.R.col(1).cwiseAbs() * c.half_extents.y() +
                    s.R.col(2).cwiseAbs() * c.half_extents.z();
  double reach = margin;
  if (dt > 0.0) {
    // A cube's ω is L / I: no rotation to and from the body frame.
    const double w = c.shape == InertiaShape::isotropic ? c.inv_inertia.x() * s.L.norm()
                                                        : angular_velocity(s, c).norm();
    reach += dt * (s.P.norm() * c.inv_mass + w * c.bounding_radius) +
             0.5 * dt * dt * gravity.norm();
  }
  const Vec3 grow = half.array() + reach;
  return {s.x - grow, s.x + grow};
}

namespace {

bool contains(const Aabb& outer, const Aabb& inner) {
  return outer.lo.x() <= inner.lo.x() && outer.lo.y() <= inner.lo.y() &&
         outer.lo.z() <= inner.lo.z() && inner.hi.x() <= outer.hi.x() &&
         inner.hi.y() <= outer.hi.y() && inner.hi.z() <= outer.hi.z();
}

/// One body's swept box and candidacy; returns whether its candidacy changed.
bool update_box(StepContext& ctx, std::uint32_t i) {
  BroadPhaseCache& k = ctx.broad;
  const Body& b = ctx.bodies[i];
  const bool awake = k.active[i] != 0;
  k.boxes[i] = swept_aabb(b.s, b.c, ctx.world.gravity, awake ? ctx.dt : 0.0,
                          0.5 * kSpeculativeDistance);
  k.box_cached[i] = !awake;
  // A body about to go non-finite (an overflowing impulse) touches nothing: it flies alone
  // and finalize freezes it.
  const std::uint8_t candidate = b.activity != Activity::frozen &&
                                 std::isfinite(k.boxes[i].lo.sum() + k.boxes[i].hi.sum());
  const bool changed = candidate != k.candidate[i];
  k.candidate[i] = candidate;
  return changed;
}

// How far ahead a fat box follows its body's flight, in steps. A body flying freely stays in
// its fat box for this many steps, so the sweep that finds the fat pairs runs about once per
// kFatSteps steps while boxes fall (Box2D's predictive fat AABBs, which stretch the box along
// the step's displacement, follow the same idea). With only the fixed margin a fall of 10,000
// cubes re-swept every 8 steps, ~90 instructions per body-step of a flight step of ~1,000.
// Measured (callgrind) against 16 steps: the first 0.5 s of 10,000 falling cubes 594 -> 549
// instructions per body-step, 2,000 cubes over 2 s 1 % fewer, `pile` 0.2 % fewer; 64 steps
// cost the 2 s fall 3.5 % more.
constexpr double kFatSteps = 32.0;

/// Lowest and highest value of d(t) = v t + ½ g t² over t ∈ [0, T].
std::pair<double, double> parabola_range(double v, double g, double T) {
  const double end = T * (v + 0.5 * g * T);
  double lo = std::min(0.0, end), hi = std::max(0.0, end);
  if (g != 0.0 && -v / g > 0.0 && -v / g < T) {
    const double apex = -0.5 * v * v / g;  // d at t = −v/g
    lo = std::min(lo, apex);
    hi = std::max(hi, apex);
  }
  return {lo, hi};
}

/// The heights (m) a body flying over the floor can reach while only the floor touches it:
/// its mechanical energy never grows there (impacts have e ≤ 1, friction only takes), so its
/// centre stays between the floor and the height its energy lifts it to; its box reaches
/// further by its largest half extent (the bounding radius) and by the swept box's reach at
/// the most speed that energy allows. Gravity must point straight down, −y.
/// v: the body's velocity, m/s.
std::pair<double, double> floor_to_apex(const Body& b, const Vec3& v, const Floor& floor,
                                        double g, double dt) {
  const Vec3 w = angular_velocity(b.s, b.c);
  const double kinetic = 0.5 * (b.s.P.dot(v) + b.s.L.dot(w)) * b.c.inv_mass;  // J/kg
  const double energy = kinetic + g * std::max(b.s.x.y() - floor.height, 0.0);  // J/kg
  const double speed = std::sqrt(2.0 * energy);  // the most the energy allows, m/s
  const double spin = std::sqrt(2.0 * energy * b.c.mass * b.c.inv_inertia.maxCoeff());
  const double reach = 0.5 * kSpeculativeDistance +
                       dt * (speed + spin * b.c.bounding_radius) + 0.5 * g * dt * dt;
  const double r = b.c.bounding_radius + reach;
  return {floor.height - r, floor.height + energy / g + r};
}

/// The box the pairs are cached for: body b's tight box grown by half its bounding radius
/// (for turns, impulses and contacts) and, while b touches nothing, swept along its
/// ballistic path for kFatSteps steps. A body in contact does not fly: stretched along its
/// fall, its box met more neighbours in a pile, which cost the pile's broad phase half again.
/// A body that was `alone` (no fat pair after the last sweep) flying over the floor under
/// gravity straight down covers, besides, every height it can reach (floor_to_apex): its fall,
/// its bounces and its landing stay inside the one box. Ten thousand separated cubes falling
/// 1–3 m left their 32-step boxes every ~32 steps and again at each bounce, and the escapes
/// set off a sweep of all of them every ~17 steps: 4.4 % of their instructions over 2 s, and
/// the boxes computed for bodies whose quiet bounds had run out 3 %. Only a body found alone
/// gets the long box: stretched down to the floor, a body of a stack or a falling pile would
/// meet every one below it (`pile` and `pyramid_large` then overflowed the pair budget).
Aabb fat_box(const Aabb& tight, const Body& b, const WorldDef& world, double dt, bool alone) {
  const double margin = 0.5 * b.c.bounding_radius;
  if (b.in_contact) return {tight.lo.array() - margin, tight.hi.array() + margin};
  const Vec3& gravity = world.gravity;
  const Vec3 v = velocity(b.s, b.c);
  Aabb fat;
  for (int i = 0; i < 3; ++i) {
    const auto [lo, hi] = parabola_range(v[i], gravity[i], kFatSteps * dt);
    fat.lo[i] = tight.lo[i] + lo - margin;
    fat.hi[i] = tight.hi[i] + hi + margin;
  }
  if (alone && world.floor && gravity.x() == 0.0 && gravity.z() == 0.0 && gravity.y() < 0.0) {
    const auto [lo, hi] = floor_to_apex(b, v, *world.floor, -gravity.y(), dt);
    fat.lo.y() = std::min(fat.lo.y(), lo - margin);
    fat.hi.y() = std::max(fat.hi.y(), hi + margin);
  }
  return fat;
}

// A body alone in its fat box (no cached pair) needs its swept box only to learn whether it
// left the fat box. Instead of the box (~130 instructions: the rotated half extents, three
// norms), a quiet body checks a bound found when its fat box was: its centre inside the fat
// box shrunk by the most the swept box can reach, its momenta no larger than allowed. The
// swept box is x ± (half + reach), with half_i = Σ_k |R_ik| h_k ≤ |h| (Cauchy–Schwarz, R's
// rows are unit) and reach = ½ speculative + dt (|P|/m + |ω| |h|) + ½ dt² |g|, |ω| ≤ |L|
// max(I⁻¹); |P| may grow by m |g| dt over each of kQuietSteps steps of fall, |L| not at all
// (no torque in flight). The check passes only while the swept box is inside the fat box, so
// the pairs are those of the box computed: a fall of 10,000 cubes skips 93 % of the boxes.
// The check itself runs where the state changes (note_moved: flight, an impulse) and where
// the bound does (set_quiet), and leaves a byte, BroadPhaseCache::inside, for the next step:
// the broad phase then reads no body that stays quiet (checking here, it read each awake
// body's record once more per step, ~14 ns a body for 10,000 cubes).

// How long a quiet bound lets a body fall, in steps: past its kFatSteps the fat box still
// holds a falling body for some steps more (its margin), and with a bound of kFatSteps a
// fall of 10,000 cubes computed a third of its boxes for nothing.
constexpr double kQuietSteps = 2.0 * kFatSteps;

/// The quiet bound of body b whose fat box was just built (none when b's box is too wide
/// for its fat box to hold it anywhere).
QuietBound quiet_bound(const Aabb& fat, const Body& b, const Vec3& gravity, double dt) {
  const BodyConstants& c = b.c;
  const double g = gravity.norm();
  const double p_max = b.s.P.norm() + c.mass * g * kQuietSteps * dt;
  const double l2 = b.s.L.squaredNorm() * (1.0 + 1e-9);
  const double w_max = std::sqrt(l2) * c.inv_inertia.maxCoeff();
  const double reach = 0.5 * kSpeculativeDistance +
                       dt * (p_max * c.inv_mass + w_max * c.bounding_radius) + 0.5 * dt * dt * g;
  // Round-off of the box as computed: relative to its size and to where it is.
  const double scale = std::max(fat.lo.cwiseAbs().maxCoeff(), fat.hi.cwiseAbs().maxCoeff());
  const double grow = (c.bounding_radius + reach) * (1.0 + 1e-9) + 1e-9 + 1e-12 * scale;
  QuietBound q;
  q.core = {fat.lo.array() + grow, fat.hi.array() - grow};
  if (!(q.core.lo.array() <= q.core.hi.array()).all() || !std::isfinite(p_max + l2)) return {};
  q.p2 = p_max * p_max;
  q.l2 = l2;
  return q;
}

/// Body i's quiet bound set to q, and whether it is within it.
void set_quiet(BroadPhaseCache& k, std::uint32_t i, const QuietBound& q, const BodyState& s) {
  k.quiet[i] = q;
  k.inside[i] = within(q, s);
}

}  // namespace

// A lone body in flight that outlives its quiet bound inside its fat box (a fall longer than
// the bound's kQuietSteps) takes a new one from the same fat box: without a sweep to hand it
// out, it computed its box every step for the rest of its long box's life. The new bound
// holds only where the swept box is inside the fat box, as every bound does. A body touching
// the floor leaves its bound at every impact, and a new one would not last.
void renew_quiet(StepContext& ctx, std::uint32_t i, const Body& b) {
  BroadPhaseCache& k = ctx.broad;
  if (!k.fat_valid || i >= k.paired.size() || k.paired[i] || k.unpaired[i] ||
      ctx.dt != k.quiet_dt || ctx.world.gravity != k.quiet_gravity)
    return;
  set_quiet(k, i, quiet_bound(k.fat[i], b, ctx.world.gravity, ctx.dt), b.s);
}

namespace {

/// Body i's box brought up to date if a quiet step skipped it, and its quiet bound dropped
/// (its fat box changed, or it has a pair whose test reads its box).
void end_quiet(StepContext& ctx, std::uint32_t i) {
  BroadPhaseCache& k = ctx.broad;
  k.quiet[i] = {};
  k.inside[i] = 0;
  if (k.stale[i]) update_box(ctx, i);  // a quiet body's candidacy stays as it was
  k.stale[i] = 0;
}

/// Every awake body's quiet bound after a sweep: none for a body in a cached pair.
void find_quiet(StepContext& ctx) {
  constexpr std::size_t kGrain = 256;
  BroadPhaseCache& k = ctx.broad;
  k.paired.assign(ctx.bodies.size(), 0);
  for (const BodyPair& p : k.fat_pairs) k.paired[p.first] = k.paired[p.second] = 1;
  k.quiet_dt = ctx.dt;
  k.quiet_gravity = ctx.world.gravity;
  ctx.pool.for_each(k.awake.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a) {
      const std::uint32_t i = k.awake[a];
      const Body& b = ctx.bodies[i];
      k.alone[i] = !k.paired[i];
      set_quiet(k, i, k.paired[i] ? QuietBound{} : quiet_bound(k.fat[i], b, ctx.world.gravity, ctx.dt),
                b.s);
    }
  });
}

/// Every body's flags and the awake list, after an activity changed (the epoch moved). A
/// sleeping body does not move: its box is computed once, when it is first seen asleep.
/// Returns whether the cached fat pairs still hold every pair that can touch, but those of
/// the bodies that woke (listed in `woken`, paired by add_woken_pairs): so when the other
/// changes are bodies falling asleep (their pairs with awake bodies are cached; the filter
/// drops pairs of two sleeping ones), each at rest inside the fat box its pairs were found
/// for, which it keeps. A body that appeared or changed candidacy needs a new sweep. In a
/// settling pile more than half of the changes are bodies falling asleep, and most of the
/// rest one or two bodies woken by a contact; each re-swept all 1,000 boxes.
bool rescan(StepContext& ctx) {
  BroadPhaseCache& k = ctx.broad;
  const std::size_t n = ctx.bodies.size();
  const std::size_t known = k.active.size();
  bool pairs_hold = k.fat_valid && known == n;
  k.epoch = ctx.cache.activity_epoch;
  k.boxes.resize(n);
  k.fat.resize(n);
  k.box_cached.resize(n, 0);
  k.active.resize(n);
  k.candidate.resize(n);
  k.unpaired.resize(n, 0);
  k.escaped.resize(n, 0);
  k.quiet.resize(n);
  k.inside.resize(n, 0);
  k.stale.resize(n, 0);
  k.alone.resize(n, 0);
  k.awake.clear();
  for (std::uint32_t i = 0; i < n; ++i) {
    const bool was_active = i < known && k.active[i];
    k.active[i] = ctx.bodies[i].activity == Activity::awake;
    if (k.active[i]) {
      if (!was_active && !k.unpaired[i]) {
        k.unpaired[i] = 1;
        k.woken.push_back(i);
      }
      k.awake.push_back(i);
      continue;
    }
    if (k.box_cached[i]) continue;
    k.stale[i] = 0;
    const bool changed = update_box(ctx, i);
    if (was_active && !changed && contains(k.fat[i], k.boxes[i])) continue;
    pairs_hold = false;
    k.fat[i] = k.boxes[i];
    k.quiet[i] = {};
    k.inside[i] = 0;
  }
  return pairs_hold;
}

/// Moves the sorted pairs `fresh`, none of them in the sorted list `pairs`, into their places
/// in it: from the back, block by block, each place found by binary search.
void merge_fresh(std::vector<BodyPair>& pairs, std::span<const BodyPair> fresh) {
  const std::size_t cached = pairs.size();
  pairs.resize(cached + fresh.size());
  auto end = pairs.begin() + static_cast<std::ptrdiff_t>(cached);  // old pairs not yet moved
  for (std::size_t j = fresh.size(); j-- > 0;) {
    const auto at = std::upper_bound(pairs.begin(), end, fresh[j]);
    const auto to = pairs.begin() + static_cast<std::ptrdiff_t>(j + 1) + (end - pairs.begin());
    std::move_backward(at, end, to);
    *(at + static_cast<std::ptrdiff_t>(j)) = fresh[j];
    end = at;
  }
}

/// Makes `added` sorted and unique again after pairs were appended past its first `cached`
/// (sorted, unique), dropping those the sweep's `swept` already holds: the new ones are sorted
/// and moved into place (merge_fresh). A merge and a unique pass over one list of every pair
/// cost ~50 instructions per cached pair, 2 % of `pile`, all of it on one thread; moving the
/// few new pairs into that list still moved all of it behind them, ~20 µs each time a body
/// left its fat box (most steps of a falling pile). The added pairs are few until the next
/// sweep: filter_pairs merges them into each step's pairs.
void add_sorted(std::vector<BodyPair>& added, std::size_t cached,
                const std::vector<BodyPair>& swept, std::vector<BodyPair>& fresh) {
  const auto old_end = added.begin() + static_cast<std::ptrdiff_t>(cached);
  fresh.clear();
  std::sort(old_end, added.end());
  for (auto it = old_end; it != added.end(); ++it)
    if ((fresh.empty() || fresh.back() != *it) && !std::binary_search(added.begin(), old_end, *it) &&
        !std::binary_search(swept.begin(), swept.end(), *it))
      fresh.push_back(*it);
  added.resize(cached);
  merge_fresh(added, fresh);
}

/// The overlap tests that pairing `count` bodies one by one is expected to cost: per body,
/// twice a body's share of the last sweep's cost (a query's range in a slab reaches back by
/// the widest interval) plus one per body refitted since.
std::size_t pairing_cost(const BroadPhaseCache& k, std::size_t count) {
  const std::size_t per_body = 2 * k.sweep.tests / std::max<std::size_t>(k.sweep.swept, 1);
  return count * (per_body + k.refit.size() + 16);
}

/// Pairs of the woken bodies (and of those that left their fat box) with every candidate
/// whose fat box meets theirs, merged into the cached pairs (sorted, each once): every pair a
/// new sweep would find, and perhaps a few it would no longer (pairs of a body's old fat box:
/// the tight boxes filter them each step, so the pairs passed on are the same). The candidates
/// come from the last sweep's orders (boxes_near) and the list of bodies refitted since, which
/// together hold every candidate with its fat box. Worth it while the expected tests cost
/// less than a sweep: at most 65,536 of them, or as many as the last sweep made. Returns false
/// past that bound, past the pair budget or once the stale pairs could have doubled the list:
/// the caller then sweeps.
bool add_woken_pairs(StepContext& ctx) {
  constexpr std::size_t kMaxTests = 1u << 16;
  BroadPhaseCache& k = ctx.broad;
  const std::size_t n = ctx.bodies.size();
  if (pairing_cost(k, k.woken.size()) > std::max(kMaxTests, k.sweep.tests)) return false;
  if (k.fat_pairs.size() + k.added_pairs.size() > 2 * k.swept_pairs + 64) return false;
  for (std::uint32_t w : k.woken) {
    k.fat[w] = fat_box(k.boxes[w], ctx.bodies[w], ctx.world, ctx.dt, k.alone[w]);
    end_quiet(ctx, w);
    if (!k.in_refit[w]) k.in_refit[w] = 1, k.refit.push_back(w);
  }
  const std::size_t cached = k.added_pairs.size();
  for (std::uint32_t w : k.woken) {
    k.near.clear();
    boxes_near(k.sweep, k.fat, k.fat[w], k.near);
    for (std::uint32_t x : k.refit)
      if (overlaps(k.fat[w], k.fat[x])) k.near.push_back(x);
    for (std::uint32_t x : k.near) {
      if (x == w || !k.candidate[x]) continue;
      k.added_pairs.emplace_back(std::min(w, x), std::max(w, x));
      k.paired[w] = k.paired[x] = 1;
      k.alone[w] = k.alone[x] = 0;
      end_quiet(ctx, x);
    }
  }
  // A sweep says which to keep.
  if (k.fat_pairs.size() + k.added_pairs.size() > pair_budget(n)) return false;
  add_sorted(k.added_pairs, cached, k.fat_pairs, k.sweep.sorted);
  // A woken body that met nobody gets its quiet bound back, as after a sweep.
  for (std::uint32_t w : k.woken)
    if (!k.paired[w])
      set_quiet(k, w, quiet_bound(k.fat[w], ctx.bodies[w], ctx.world.gravity, ctx.dt),
                ctx.bodies[w].s);
  return true;
}

/// Lists the `escaped` bodies that left their fat box with the woken ones, to be paired the
/// same way (add_woken_pairs), when a quarter of the last sweep's overlap tests pays for it; false
/// (nothing listed): sweep. A sweep renews every fat box at once: over separated boxes, whose
/// sweeps cost a few tests per box, pairing each body as it leaves cost more than the sweep
/// once every kFatSteps steps. A 3-D pile's sweep makes over a thousand tests per box, and
/// its boxes in contact (their fat boxes are tight) leave them by the hundred every few steps.
/// The bound counts n tests per body, what pairing one cost before boxes_near, although a
/// query now costs far fewer: letting more bodies through by the query's cost (pairing_cost)
/// left more of them without the fresh fat box and quiet bound a sweep hands out, and the
/// broad phase of 10,000 falling cubes took 20 % longer (before the sweep had slabs; with
/// them the two bounds measured the same, and sweeping at every escape 20 % slower).
bool pair_escaped(BroadPhaseCache& k, std::size_t escaped, std::size_t n) {
  if ((k.woken.size() + escaped) * n > k.sweep.tests / 4) return false;
  for (std::uint32_t i : k.awake)
    if (k.escaped[i]) k.unpaired[i] = 1, k.woken.push_back(i);
  return true;
}

/// The cached pairs whose swept boxes overlap, one body awake, into scratch.pairs in their
/// order. In `pile` that is thousands of pairs a step, a fifth of the broad phase: shared
/// among the pool's threads in fixed ranges of the pairs, each kept in a list of its own (the
/// sweep's, free once its pairs are joined) and joined in range order, so the same list on
/// any thread count. The added pairs' are merged in after (merge_fresh).
void filter_pairs(StepContext& ctx) {
  constexpr std::size_t kGrain = 2048;  // pairs per range: ~10 ns each
  BroadPhaseCache& k = ctx.broad;
  const std::uint8_t* active = k.active.data();
  const Aabb* boxes = k.boxes.data();
  // Every pair is written and the count moves on only for those kept: no branch on the test.
  auto keep = [&](std::span<const BodyPair> pairs, std::vector<BodyPair>& out) {
    std::size_t count = out.size();
    out.resize(count + pairs.size());
    BodyPair* to = out.data();
    for (const BodyPair& p : pairs) {
      to[count] = p;
      const bool awake = (active[p.first] | active[p.second]) != 0;
      count += int{awake} & int{overlaps(boxes[p.first], boxes[p.second])};
    }
    out.resize(count);
  };
  // Local views: through `k` every push_back would reload the lists it might have changed.
  const std::span<const BodyPair> pairs(k.fat_pairs);
  const std::size_t n = pairs.size();
  const std::size_t ranges = std::min<std::size_t>(4 * ctx.pool.size(), n / kGrain);
  if (ranges < 2) {
    keep(pairs, ctx.scratch.pairs);
  } else {
    std::vector<std::vector<BodyPair>>& parts = k.sweep.range_pairs;
    if (parts.size() < ranges) parts.resize(ranges);
    ctx.pool.for_each(ranges, 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t r = begin; r < end; ++r) {
        parts[r].clear();
        keep(pairs.subspan(n * r / ranges, n * (r + 1) / ranges - n * r / ranges), parts[r]);
      }
    });
    for (std::size_t r = 0; r < ranges; ++r)
      ctx.scratch.pairs.insert(ctx.scratch.pairs.end(), parts[r].begin(), parts[r].end());
  }
  if (k.added_pairs.empty()) return;
  std::vector<BodyPair>& added = k.sweep.sorted;  // the sweep's sort scratch, free here
  added.clear();
  keep(k.added_pairs, added);
  merge_fresh(ctx.scratch.pairs, added);
}

/// Every awake body's fat box anew (the long box for those found alone, with `long_boxes`),
/// and the sweep that pairs them; returns whether the pairs fit the budget.
bool sweep_fat_boxes(StepContext& ctx, bool long_boxes) {
  constexpr std::size_t kGrain = 256;  // bodies per chunk
  BroadPhaseCache& k = ctx.broad;
  ctx.pool.for_each(k.awake.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t a = begin; a < end; ++a) {
      const std::uint32_t i = k.awake[a];
      if (k.stale[i]) update_box(ctx, i);
      k.stale[i] = 0;
      k.fat[i] = fat_box(k.boxes[i], ctx.bodies[i], ctx.world, ctx.dt, long_boxes && k.alone[i]);
    }
  });
  return find_pairs(k.fat, k.active, k.candidate, k.awake, k.epoch, k.sweep, k.fat_pairs,
                    pair_budget(ctx.bodies.size()), ctx.pool);
}

void clear_woken(BroadPhaseCache& k) {
  for (std::uint32_t w : k.woken) k.unpaired[w] = 0;
  k.woken.clear();
}

}  // namespace

// Pairs from fattened boxes, reused while every awake body stays inside its fat box and no
// body changes activity (Box2D's fat AABBs, Catto 2019 "Dynamic bounding volume
// hierarchies"), stretched along each body's flight (fat_box): the sweep runs about once
// every kFatSteps steps and the steps between only filter the cached pairs by the tight boxes.
// Between changes of activity (counted by ContactCache::activity_epoch) a step touches only
// the awake bodies: 10,000 sleeping boxes cost nothing.
void broad_phase(StepContext& ctx) {
  constexpr std::size_t kGrain = 256;  // bodies per chunk: ~30 ns each
  StepScratch& s = ctx.scratch;
  BroadPhaseCache& k = ctx.broad;
  s.pairs.clear();
  const std::size_t n = ctx.bodies.size();
  const bool full = k.epoch != ctx.cache.activity_epoch || k.active.size() != n;
  if (full && !rescan(ctx)) k.fat_valid = false;
  // Each awake body's box on its own, shared among the pool's threads; the flags are ORed.
  std::atomic<bool> rebuild = !k.fat_valid;
  std::atomic<std::size_t> escaped = 0;
  const bool quiet = k.fat_valid && ctx.dt == k.quiet_dt && ctx.world.gravity == k.quiet_gravity;
  ctx.pool.for_each(k.awake.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    bool changed = false;
    std::size_t left = 0;
    for (std::size_t a = begin; a < end; ++a) {
      const std::uint32_t i = k.awake[a];
      k.stale[i] = quiet && !k.unpaired[i] && k.inside[i];
      if (k.stale[i]) {
        k.escaped[i] = 0;
        continue;
      }
      changed = update_box(ctx, i) || changed;
      k.escaped[i] = !k.unpaired[i] && !contains(k.fat[i], k.boxes[i]);
      left += k.escaped[i];
    }
    if (changed) rebuild.store(true, std::memory_order_relaxed);
    if (left) escaped.fetch_add(left, std::memory_order_relaxed);
  });
  if (n < 2 || k.awake.empty()) return;
  if (!rebuild.load() && escaped.load() > 0 && !pair_escaped(k, escaped.load(), n))
    rebuild.store(true);
  if (!rebuild.load() && !k.woken.empty() && !add_woken_pairs(ctx)) rebuild.store(true);
  clear_woken(k);
  if (rebuild.load()) {
    k.fat_complete = sweep_fat_boxes(ctx, true);
    // The long boxes of bodies found alone must never cost a pair the scene's own packing
    // would not: past the budget, the sweep is taken again without them.
    if (!k.fat_complete && std::any_of(k.awake.begin(), k.awake.end(),
                                       [&](std::uint32_t i) { return k.alone[i] != 0; }))
      k.fat_complete = sweep_fat_boxes(ctx, false);
    k.added_pairs.clear();
    k.swept_pairs = k.fat_pairs.size();
    k.fat_valid = true;
    k.in_refit.resize(n);
    for (std::uint32_t i : k.refit) k.in_refit[i] = 0;
    k.refit.clear();
    find_quiet(ctx);
  }
  filter_pairs(ctx);
  ctx.stats.pairs = static_cast<std::uint32_t>(s.pairs.size());
  ctx.stats.pair_budget_exceeded = k.fat_complete ? 0 : 1;
}

}  // namespace tumble

namespace tumble {

std::size_t initial_pairs(std::span<const Body> bodies, const Vec3& gravity) {
  const std::size_t n = bodies.size();
  std::vector<Aabb> boxes(n);
  std::vector<std::uint8_t> active(n, 1), candidate(n, 1);
  for (std::size_t i = 0; i < n; ++i)
    boxes[i] = swept_aabb(bodies[i].s, bodies[i].c, gravity, 0.0, 0.5 * kSpeculativeDistance);
  SweepScratch sweep;
  std::vector<BodyPair> pairs;
  std::vector<std::uint32_t> all(n);
  for (std::size_t i = 0; i < n; ++i) all[i] = static_cast<std::uint32_t>(i);
  WorkerPool alone(1);
  find_pairs(boxes, active, candidate, all, 0, sweep, pairs, pair_budget(n) + 1, alone);
  return pairs.size();
}

}  // namespace tumble
