#include <algorithm>

#include "floor_contact.hpp"
#include "pipeline.hpp"

namespace tumble {
namespace {

// One rule for every island, a lone body being an island of one (Box2D v3's rule, Catto 2023
// "Simulation islands"): a body is still while it touches something and its fastest point
// moves slower than kSleepSpeed; an island whose bodies have all been still for kSleepTime
// sleeps as a whole, with its momenta zeroed so that it is exactly at rest.
constexpr double kSleepSpeed = 0.05;  // m/s
constexpr double kSleepTime = 0.5;    // s

// A body that rocks in place is still too: every point within kSleepReach of where it was when
// its still time began (Jolt's sleep test, which bounds how far a body's points wander over the
// sleep time instead of their speed). The reach is the distance the speed rule lets a still
// body cover in the sleep time. Why: a box wedged between two others, or balanced on two
// supports, can rock on its contacts like a pendulum, which rigid contacts do not damp; its
// points then pass 0.05–0.15 m/s at the bottom of each swing while staying within a few
// millimetres, and the speed rule alone kept 8 of 30 `pile` sizes (200–490 boxes) awake for
// the whole 30 s, every body of the box's island with it.
constexpr double kSleepReach = kSleepSpeed * kSleepTime;  // 2.5 cm

SleepAnchor anchor_of(const BodyState& s) { return {s.x.cast<float>(), s.R.cast<float>()}; }

// A bound on how far any point of the body has moved from the anchor: its centre's move plus
// its bounding radius times ‖R − R₀‖ (the Frobenius norm bounds the spectral one).
double moved_from(const SleepAnchor& a, const BodyState& s, const BodyConstants& c) {
  return (s.x - a.x.cast<double>()).norm() + c.bounding_radius * (s.R - a.R.cast<double>()).norm();
}

// A body at rest on a face on the floor (momenta zero to 1e-12, three or more corners within
// the resting contact's 1e-6 m of the floor: the exact floor contact leaves a landed box so) is in static equilibrium already:
// the timer, there to tell a pause from rest, has nothing to tell, and the body counts as
// still for all of it. As a body placed so starts asleep (World's constructor), a box that
// lands and stops on a face sleeps at once instead of 0.5 s later. A box that stops
// momentarily on an edge (two corners) still waits for the timer.
void update_still_time(Body& b, SleepAnchor& anchor, double dt, const WorldDef& world) {
  if (b.activity != Activity::awake) return;
  if (!b.in_contact) {  // in flight: nothing to keep (the anchor is not touched)
    b.still_time = 0.0;
    return;
  }
  if (b.still_time == 0.0) anchor = anchor_of(b.s);
  const bool still = point_speed_bound(b.s, b.c) <= kSleepSpeed ||
                     moved_from(anchor, b.s, b.c) <= kSleepReach;
  b.still_time = still ? b.still_time + dt : 0.0;
  if (still && world.floor && at_rest_on_face(b.s, b.c, world.floor->height))
    b.still_time = std::max(b.still_time, kSleepTime);
}

bool ready_to_sleep(const Body& b) {
  return b.activity == Activity::awake && b.still_time >= kSleepTime;
}

/// Body b asleep, exactly at rest.
void rest(Body& b) {
  b.activity = Activity::asleep;
  b.s.P.setZero();
  b.s.L.setZero();
}

/// Puts the island `members` to sleep as one ring; the caller moves the activity epoch.
void fall_asleep(ContactCache& cache, std::span<Body> bodies,
                 std::span<const std::uint32_t> members) {
  for (std::size_t n = 0; n < members.size(); ++n) {
    rest(bodies[members[n]]);
    cache.sleep_next[members[n]] = members[(n + 1) % members.size()];
  }
}

// A lone box held by the floor on an edge or a corner only, with gravity pressing it into the
// floor, is at best balanced unstably: its centre of mass must lie exactly above the support,
// and any offset grows as an inverted pendulum's, e^(λt) with λ = √(1.5 g d) for a cube about
// an edge (3.2 /s for a unit cube). Near balance it turns slowly enough to pass the speed and
// reach tests, and the timer put a unit cube placed 0.001 rad past balance to sleep after
// 0.5 s, frozen 0.0028 rad past it for good. Such a body is not still: it sleeps once it has
// come down on a face (at_rest_on_face), at its exact rest. A body leaning on another is in an
// island and keeps the island rule (it can be held so).
bool balanced_on_edge_or_corner(const Body& b, const WorldDef& world) {
  return world.floor && world.gravity.y() < 0.0 && b.in_contact &&
         touches_floor_on_edge_or_corner(b.s, b.c, world.floor->height);
}

}  // namespace

void init_caches(ContactCache& cache, std::size_t body_count) {
  const std::size_t before = cache.sleep_next.size();
  cache.sleep_next.resize(body_count);
  for (std::size_t i = before; i < body_count; ++i) cache.sleep_next[i] = static_cast<std::uint32_t>(i);
  cache.anchors.resize(body_count);
}

// The epoch moves only when a body's activity changes: an impulse on an awake body (the
// benchmarks keep scenes awake with zero impulses) leaves the broad phase's caches valid.
void wake_island(ContactCache& cache, std::span<Body> bodies, std::uint32_t id) {
  std::uint32_t i = id;
  do {
    Body& b = bodies[i];
    if (b.activity == Activity::asleep) {
      b.activity = Activity::awake;
      ++cache.activity_epoch;
    }
    b.still_time = 0.0;
    const std::uint32_t next = cache.sleep_next[i];
    cache.sleep_next[i] = i;
    i = next;
  } while (i != id);
}

bool settle_lone_body(Body& b, std::uint32_t id, ContactCache& cache, double dt,
                      const WorldDef& world) {
  update_still_time(b, cache.anchors[id], dt, world);
  if (b.still_time > 0.0 && balanced_on_edge_or_corner(b, world)) b.still_time = 0.0;
  if (!ready_to_sleep(b)) return false;
  rest(b);
  cache.sleep_next[id] = id;  // a ring of one
  return true;
}

// Lone bodies took the rule in flight (settle_lone_body); the islands take it here.
void update_sleep(StepContext& ctx) {
  constexpr std::size_t kGrain = 256;  // bodies per chunk: ~20 ns each
  StepScratch& s = ctx.scratch;
  // Each island body's still time on its own, shared among the pool's threads (it writes
  // only that body's time and anchor); the islands then fall asleep in order.
  ctx.pool.for_each(s.solver_bodies.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const std::uint32_t id = s.solver_bodies[k];
      update_still_time(ctx.bodies[id], ctx.cache.anchors[id], ctx.dt, ctx.world);
    }
  });
  for (std::size_t k = 0; k < s.island.count(); ++k) {
    const std::span<const std::uint32_t> members = s.island.island(k);
    bool still = true;
    for (std::uint32_t id : members) still = still && ready_to_sleep(ctx.bodies[id]);
    if (!still) continue;
    fall_asleep(ctx.cache, ctx.bodies, members);
    ++ctx.cache.activity_epoch;
  }
}

}  // namespace tumble
