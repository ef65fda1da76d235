#include "contact_stage.hpp"

#include <algorithm>
#include <cmath>

#include "box_box.hpp"

namespace tumble {
namespace {

// An island sleeps when each of its bodies has moved slower than this (fastest point, m/s)
// for kIslandSleepTime: Box2D v3's rule (0.05 m/s for 0.5 s), whole islands together.
constexpr double kIslandSleepSpeed = 0.05;
constexpr double kIslandSleepTime = 0.5;
constexpr int kMaxWakeRounds = 8;
// A body pair joins the contact solve only when a point of its manifold is closer than this
// (m) or will close its gap within the step at the current velocities. Pairs that merely pass
// near each other keep the floor-only path with the scene's exact integrator.
constexpr double kTouchDistance = 1e-3;

/// True when some point of the manifold touches or will touch within dt.
bool touches(const BoxManifold& m, const Body& a, const Body& b, double dt) {
  const Vec3 va = a.s.P * a.c.inv_mass, vb = b.s.P * b.c.inv_mass;
  const Vec3 wa = angular_velocity(a.s, a.c), wb = angular_velocity(b.s, b.c);
  for (int i = 0; i < m.count; ++i) {
    const Vec3& p = m.points[i].position;
    const double vn = (vb + wb.cross(p - b.s.x) - va - wa.cross(p - a.s.x)).dot(m.normal);
    if (m.points[i].separation + std::min(vn, 0.0) * dt <= kTouchDistance) return true;
  }
  return false;
}

std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) {
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

/// Fastest point of a body: |v| + |ω| r, m/s.
double point_speed_bound(const Body& b) {
  return b.s.P.norm() * b.c.inv_mass + angular_velocity(b.s, b.c).norm() * b.c.bounding_radius;
}

bool contains(const Aabb& outer, const Aabb& inner) {
  return (outer.lo.array() <= inner.lo.array()).all() && (inner.hi.array() <= outer.hi.array()).all();
}

bool overlaps(const Aabb& a, const Aabb& b) {
  return (a.lo.array() <= b.hi.array()).all() && (b.lo.array() <= a.hi.array()).all();
}

// Pairs from fattened boxes, reused while every awake body stays inside its fat box and no
// body changes activity (Box2D's fat AABBs, Catto 2019 "Dynamic bounding volume
// hierarchies"): a falling box moves a few centimetres a step, so the sweep runs about once
// every ten steps and the steps between only filter the cached pairs by the tight boxes.
void broad_phase(ContactState& k, std::span<const Body> bodies) {
  const std::size_t n = bodies.size();
  bool rebuild = k.fat.size() != n;
  std::uint64_t signature = 1469598103934665603ull;
  for (std::size_t i = 0; i < n && !rebuild; ++i) {
    signature = (signature ^ (k.active[i] | (k.candidate[i] << 1))) * 1099511628211ull;
    if (k.active[i] && !contains(k.fat[i], k.boxes[i])) rebuild = true;
  }
  if (rebuild || signature != k.fat_signature) {
    k.fat.resize(n);
    signature = 1469598103934665603ull;
    for (std::size_t i = 0; i < n; ++i) {
      signature = (signature ^ (k.active[i] | (k.candidate[i] << 1))) * 1099511628211ull;
      const double margin = k.active[i] ? 0.5 * bodies[i].c.bounding_radius : 0.0;
      k.fat[i] = {k.boxes[i].lo.array() - margin, k.boxes[i].hi.array() + margin};
    }
    k.fat_signature = signature;
    find_pairs(k.fat, k.active, k.candidate, k.sweep, k.fat_pairs);
  }
  k.pairs.clear();
  for (const BodyPair& p : k.fat_pairs)
    if (overlaps(k.boxes[p.first], k.boxes[p.second])) k.pairs.push_back(p);
}

/// Broad and narrow phase over the current activity flags; fills k.contacts with the
/// body–body contacts. Returns how many sleeping bodies a contact touched (and woke).
int collide(ContactState& k, std::span<Body> bodies, const WorldDef& w, double dt) {
  const std::size_t n = bodies.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Body& b = bodies[i];
    k.active[i] = b.activity == Activity::awake;
    // A sleeping body does not move: its box (and candidacy) is computed once, when it is
    // first seen asleep, so 10,000 sleeping boxes cost a flag test each per step.
    if (!k.active[i] && k.box_cached[i]) continue;
    k.boxes[i] = swept_aabb(b.s, b.c, w.gravity, k.active[i] ? dt : 0.0,
                            0.5 * kSpeculativeDistance);
    k.box_cached[i] = !k.active[i];
    // A body about to go non-finite (an overflowing impulse) touches nothing: the floor-only
    // path freezes it after its step.
    k.candidate[i] = b.activity != Activity::frozen &&
                     std::isfinite(k.boxes[i].lo.sum() + k.boxes[i].hi.sum());
  }
  broad_phase(k, bodies);
  k.contacts.clear();
  int woken = 0;
  for (const BodyPair& p : k.pairs) {
    Body& a = bodies[p.first];
    Body& b = bodies[p.second];
    const double closing = dt * ((a.s.P * a.c.inv_mass - b.s.P * b.c.inv_mass).norm() +
                                 angular_velocity(a.s, a.c).norm() * a.c.bounding_radius +
                                 angular_velocity(b.s, b.c).norm() * b.c.bounding_radius);
    const BoxManifold m = collide_boxes(a.s, a.c, b.s, b.c, kSpeculativeDistance + closing);
    if (m.count == 0 || !touches(m, a, b, dt)) continue;
    Contact c;
    c.a = p.first;
    c.b = p.second;
    c.normal = m.normal;
    c.friction = std::sqrt(a.c.friction * b.c.friction);
    c.restitution = std::max(a.c.restitution, b.c.restitution);
    c.count = m.count;
    for (int i = 0; i < m.count; ++i) {
      c.points[i].position = m.points[i].position;
      c.points[i].separation = m.points[i].separation;
      c.points[i].id = m.points[i].id;
    }
    k.contacts.push_back(c);
    for (Body* body : {&a, &b}) {
      if (body->activity != Activity::asleep) continue;
      wake_island(k, bodies, static_cast<std::uint32_t>(body == &a ? p.first : p.second));
      ++woken;
    }
  }
  return woken;
}

}  // namespace

void init_contact_state(ContactState& k, std::size_t body_count) {
  k.sleep_next.resize(body_count);
  for (std::size_t i = 0; i < body_count; ++i) k.sleep_next[i] = static_cast<std::uint32_t>(i);
  k.boxes.resize(body_count);
  k.active.resize(body_count);
  k.candidate.resize(body_count);
  k.box_cached.assign(body_count, 0);
  k.in_solver.assign(body_count, 0);
}

void wake_island(ContactState& k, std::span<Body> bodies, std::uint32_t id) {
  std::uint32_t i = id;
  do {
    Body& b = bodies[i];
    if (b.activity == Activity::asleep) b.activity = Activity::awake;
    b.still_time = 0.0;
    const std::uint32_t next = k.sleep_next[i];
    k.sleep_next[i] = i;
    i = next;
  } while (i != id);
}

bool find_contacts(ContactState& k, std::span<Body> bodies, const WorldDef& w, double dt,
                   StepStats& stats) {
  std::fill(k.in_solver.begin(), k.in_solver.end(), 0);
  k.contacts.clear();
  if (bodies.size() < 2) return false;
  const bool any_awake = std::any_of(bodies.begin(), bodies.end(), [](const Body& b) {
    return b.activity == Activity::awake;
  });
  if (!any_awake) {
    k.previous.clear();
    k.previous_index.clear();
    return false;
  }
  // A contact with a sleeping island wakes it; its bodies then need their own contacts.
  for (int round = 0; round < kMaxWakeRounds; ++round)
    if (collide(k, bodies, w, dt) == 0) break;
  stats.pairs = static_cast<std::uint32_t>(k.pairs.size());
  if (k.contacts.empty()) {
    k.previous.clear();
    k.previous_index.clear();
    return false;
  }

  k.links.clear();
  for (const Contact& c : k.contacts) {
    k.links.emplace_back(c.a, c.b);
    stats.contact_points += static_cast<std::uint32_t>(c.count);
  }
  stats.contacts = static_cast<std::uint32_t>(k.contacts.size());
  k.islands = build_islands(bodies.size(), k.links, k.sets, k.island_of);
  stats.islands = static_cast<std::uint32_t>(k.islands.size());
  k.solver_bodies.clear();
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    if (k.island_of[i] < 0) continue;
    k.in_solver[i] = 1;
    k.solver_bodies.push_back(static_cast<std::uint32_t>(i));
  }
  stats.solver_bodies = static_cast<std::uint32_t>(k.solver_bodies.size());

  // The floor joins the same solve as a static body, so a stack's bottom box feels both its
  // load and the floor in one consistent set of impulses. Floor contacts go first: Gauss–
  // Seidel then carries the support up the stack within one sweep.
  if (w.floor) {
    // A body struck from above can be driven down faster than it moves now: its floor margin
    // also covers the speed of the fastest body touching it.
    k.reach.assign(bodies.size(), 0.0);
    for (const Contact& c : k.contacts) {
      k.reach[c.a] = std::max(k.reach[c.a], point_speed_bound(bodies[c.b]));
      k.reach[c.b] = std::max(k.reach[c.b], point_speed_bound(bodies[c.a]));
    }
    std::vector<Contact> floor;
    for (std::uint32_t id : k.solver_bodies) {
      const Body& b = bodies[id];
      Contact c;
      const double margin = kSpeculativeDistance + dt * (point_speed_bound(b) + k.reach[id]);
      if (floor_contact(b.s, b.c, id, w.floor->height, margin, c) > 0) floor.push_back(c);
    }
    k.contacts.insert(k.contacts.begin(), floor.begin(), floor.end());
  }
  for (Contact& c : k.contacts) {
    const auto it = k.previous_index.find(pair_key(c.a, c.b));
    if (it != k.previous_index.end()) warm_start_from(c, k.previous[it->second]);
  }
  return true;
}

void step_contacts(ContactState& k, std::span<Body> bodies, const WorldDef& w, double dt,
                   bool renormalize, StepStats& stats) {
  k.before.clear();
  for (std::uint32_t id : k.solver_bodies) k.before.push_back(bodies[id].s);
  stats.impacts += static_cast<std::uint32_t>(
      solve_contacts(bodies, k.solver_bodies, k.contacts, w.gravity, dt, k.settings,
                     k.solver_index));
  stats.awake += static_cast<std::uint32_t>(k.solver_bodies.size());
  for (std::size_t n = 0; n < k.solver_bodies.size(); ++n) {
    Body& b = bodies[k.solver_bodies[n]];
    const BodyState& s = b.s;
    if (!std::isfinite(s.x.sum() + s.P.sum() + s.L.sum() + s.R.sum())) {
      b.s = k.before[n];
      b.activity = Activity::frozen;
      ++stats.newly_frozen;
      continue;
    }
    if (renormalize) gram_schmidt(b.s.R);
    b.in_contact = true;
    b.still_time = point_speed_bound(b) > kIslandSleepSpeed ? 0.0 : b.still_time + dt;
  }
  for (const std::vector<std::uint32_t>& island : k.islands) {
    bool still = true;
    for (std::uint32_t id : island)
      still = still && bodies[id].activity == Activity::awake &&
              bodies[id].still_time >= kIslandSleepTime;
    if (!still) continue;
    for (std::size_t n = 0; n < island.size(); ++n) {
      Body& b = bodies[island[n]];
      b.activity = Activity::asleep;
      b.s.P.setZero();
      b.s.L.setZero();
      k.sleep_next[island[n]] = island[(n + 1) % island.size()];
    }
  }
  // Keep this step's impulses for the next step's warm start.
  std::swap(k.previous, k.contacts);
  k.contacts.clear();
  k.previous_index.clear();
  for (std::size_t i = 0; i < k.previous.size(); ++i)
    k.previous_index.emplace(pair_key(k.previous[i].a, k.previous[i].b),
                             static_cast<std::uint32_t>(i));
}

}  // namespace tumble
