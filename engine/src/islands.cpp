#include "islands.hpp"

#include <algorithm>

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
// anywhere in a stack reaches every body of it within one solve.
std::vector<std::vector<std::uint32_t>> build_islands(std::size_t body_count,
                                                      std::span<const BodyPair> links,
                                                      UnionFind& sets,
                                                      std::vector<std::int32_t>& island) {
  sets.reset(body_count);
  island.assign(body_count, -1);
  std::vector<std::uint8_t> linked(body_count, 0);
  for (const BodyPair& p : links) {
    sets.unite(p.first, p.second);
    linked[p.first] = linked[p.second] = 1;
  }
  std::vector<std::vector<std::uint32_t>> islands;
  std::vector<std::int32_t> root_island(body_count, -1);
  for (std::uint32_t i = 0; i < body_count; ++i) {
    if (!linked[i]) continue;
    const std::uint32_t r = sets.find(i);
    if (root_island[r] < 0) {
      root_island[r] = static_cast<std::int32_t>(islands.size());
      islands.emplace_back();
    }
    island[i] = root_island[r];
    islands[root_island[r]].push_back(i);
  }
  return islands;
}

}  // namespace tumble
