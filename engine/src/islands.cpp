#include "islands.hpp"

#include <algorithm>

#include "pipeline.hpp"

namespace tumble {

void UnionFind::reset(std::size_t n) {
  parent_.resize(n);
  for (std::size_t i = 0; i < n; ++i) parent_[i] = static_cast<std::uint32_t>(i);
}

std::uint32_t UnionFind::find(std::uint32_t i) {
  while (parent_[i] != i) {
    parent_[i] = parent_[parent_[i]];
    i = parent_[i];
  }
  return i;
}

void UnionFind::unite(std::uint32_t a, std::uint32_t b) {
  a = find(a);
  b = find(b);
  if (a == b) return;
  if (a < b) parent_[b] = a;
  else parent_[a] = b;
}

// Islands as in Box2D (Catto 2023, "Simulation islands"): contacts are the edges of a graph
// over bodies; its connected components move, sleep and wake together, because an impulse
// anywhere in a stack reaches every body of it within one solve. Two passes over the linked
// bodies in ascending order (count, then place) give the compressed lists without sorting.
void build_islands(std::size_t body_count, std::span<const BodyPair> links, IslandScratch& out) {
  out.sets.reset(body_count);
  out.island_of.assign(body_count, -1);
  for (const BodyPair& p : links) out.sets.unite(p.first, p.second);
  // Linked bodies are marked −2 first; the root's island number is taken when met first.
  for (const BodyPair& p : links) out.island_of[p.first] = out.island_of[p.second] = -2;
  out.offset.assign(1, 0);
  std::vector<std::int32_t>& of = out.island_of;
  for (std::uint32_t i = 0; i < body_count; ++i) {
    if (of[i] == -1) continue;
    const std::uint32_t r = out.sets.find(i);
    if (r == i) {  // the smallest member is the root: a new island
      of[i] = static_cast<std::int32_t>(out.offset.size() - 1);
      out.offset.push_back(0);
    } else {
      of[i] = of[r];
    }
    ++out.offset[of[i] + 1];
  }
  for (std::size_t k = 1; k < out.offset.size(); ++k) out.offset[k] += out.offset[k - 1];
  out.members.resize(out.offset.back());
  out.cursor.assign(out.offset.begin(), out.offset.end() - 1);
  for (std::uint32_t i = 0; i < body_count; ++i)
    if (of[i] >= 0) out.members[out.cursor[of[i]]++] = i;
}

void islands(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  const std::size_t n = ctx.bodies.size();
  s.solver_bodies.clear();
  s.lone_bodies.clear();
  if (s.links.empty()) {
    s.island.offset.clear();
  } else {
    build_islands(n, s.links, s.island);
    // The islands' members, ascending, are the linked bodies the narrow phase listed in that
    // order (sorting the members again was a third of this stage in `pile`).
    s.solver_bodies.assign(s.linked.begin(), s.linked.end());
  }
  // The broad phase's awake list is current unless the last detection round woke bodies.
  if (ctx.broad.epoch == ctx.cache.activity_epoch) {
    for (std::uint32_t i : ctx.broad.awake)
      if (s.links.empty() || s.island.island_of[i] < 0) s.lone_bodies.push_back(i);
  } else {
    for (std::uint32_t i = 0; i < n; ++i)
      if (ctx.bodies[i].activity == Activity::awake &&
          (s.links.empty() || s.island.island_of[i] < 0))
        s.lone_bodies.push_back(i);
  }
  // The island bodies' start states, for finalize (flight keeps a lone body's as it reads it).
  s.before.resize(s.solver_bodies.size());
  ctx.pool.for_each(s.solver_bodies.size(), 1024, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) s.before[k] = ctx.bodies[s.solver_bodies[k]].s;
  });
  ctx.stats.islands = static_cast<std::uint32_t>(s.island.count());
  ctx.stats.solver_bodies = static_cast<std::uint32_t>(s.solver_bodies.size());
  ctx.stats.awake = static_cast<std::uint32_t>(s.solver_bodies.size() + s.lone_bodies.size());
}

}  // namespace tumble
