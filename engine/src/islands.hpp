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

/// The islands of `bodies` linked by `links`: island[i] is the index (into the returned list
/// of member lists) of body i's island, for the bodies that appear in a link; others get -1.
/// Islands are numbered by their smallest body index, members listed in ascending order.
std::vector<std::vector<std::uint32_t>> build_islands(std::size_t body_count,
                                                      std::span<const BodyPair> links,
                                                      UnionFind& sets,
                                                      std::vector<std::int32_t>& island);

}  // namespace tumble
