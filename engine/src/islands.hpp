#pragma once
/// Islands: bodies linked by contacts, found by union–find. An island sleeps when every body
/// in it has been still for long enough, and wakes as a whole. Pure functions over the
/// caller's buffers; thread-safe.
#include <cstdint>
#include <span>
#include <vector>

#include "broad_phase.hpp"

namespace tumble {

/// Disjoint sets over body indices with path halving and union by index (the smaller index
/// becomes the root, so the result does not depend on the order of unions: deterministic).
class UnionFind {
 public:
  /// n singleton sets.
  void reset(std::size_t n);
  /// Representative of i's set.
  std::uint32_t find(std::uint32_t i);
  /// Merges the sets of a and b.
  void unite(std::uint32_t a, std::uint32_t b);

 private:
  std::vector<std::uint32_t> parent_;
};

/// Islands of linked bodies in compressed form, reused between steps (no allocation once
/// warm). Island k's members are members[offset[k] .. offset[k + 1]), ascending; islands are
/// numbered by their smallest body index.
struct IslandScratch {
  UnionFind sets;                       ///< Union–find over all bodies.
  std::vector<std::int32_t> island_of;  ///< Island of each body, −1 when in no link.
  std::vector<std::uint32_t> members;   ///< Bodies of all islands, island by island.
  std::vector<std::uint32_t> offset;    ///< Start of each island in members, plus the end.
  std::vector<std::uint32_t> cursor;    ///< Fill position of each island while building.
  /// Number of islands.
  std::size_t count() const { return offset.empty() ? 0 : offset.size() - 1; }
  /// Members of island k.
  std::span<const std::uint32_t> island(std::size_t k) const {
    return {members.data() + offset[k], members.data() + offset[k + 1]};
  }
};

/// Fills `out` with the islands of `body_count` bodies linked by `links`.
void build_islands(std::size_t body_count, std::span<const BodyPair> links, IslandScratch& out);

}  // namespace tumble
