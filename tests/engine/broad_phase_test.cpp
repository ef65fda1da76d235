// The broad phase's pair search (find_pairs, engine/src/sweep_and_prune.cpp): every pair of
// overlapping boxes with an awake one, each once and in order, whatever the boxes' sizes,
// places and number of threads, checked against testing every pair.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "broad_phase.hpp"

namespace tumble {
namespace {

struct Boxes {
  std::vector<Aabb> boxes;
  std::vector<std::uint8_t> active, candidate;
  std::vector<std::uint32_t> awake;
};

/// n boxes of mixed widths: most about 1 m in a dense heap, some stretched tall (a fat box
/// following a fall), some tiny, a few huge or far away; a share asleep, a few not candidates.
Boxes mixed_boxes(std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Boxes b;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 centre(8.0 * unit(rng), 8.0 * unit(rng), 8.0 * unit(rng));
    Vec3 half = Vec3::Constant(0.3 + 0.5 * unit(rng));
    const double kind = unit(rng);
    if (kind < 0.15) half.y() *= 6.0;                   // stretched along a fall
    else if (kind < 0.25) half *= 0.01;                 // tiny
    else if (kind < 0.28) half *= 40.0;                 // huge
    Vec3 c = centre;
    if (kind > 0.98) c.x() = 1e14;                      // too far for the grid's cells
    b.boxes.push_back({c - half, c + half});
    b.active.push_back(unit(rng) < 0.7);
    b.candidate.push_back(unit(rng) < 0.97);
    if (b.active.back()) b.awake.push_back(static_cast<std::uint32_t>(i));
  }
  return b;
}

/// Every pair with a candidate awake body, by testing each pair.
std::vector<BodyPair> all_pairs(const Boxes& b) {
  std::vector<BodyPair> pairs;
  for (std::uint32_t i = 0; i < b.boxes.size(); ++i)
    for (std::uint32_t j = i + 1; j < b.boxes.size(); ++j)
      if (b.candidate[i] && b.candidate[j] && (b.active[i] || b.active[j]) &&
          overlaps(b.boxes[i], b.boxes[j]))
        pairs.emplace_back(i, j);
  return pairs;
}

TEST(BroadPhase, FindsEveryOverlappingPairOnceInOrderForAnyThreadCount) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const Boxes b = mixed_boxes(600, seed);
    const std::vector<BodyPair> expected = all_pairs(b);
    ASSERT_GT(expected.size(), 600u) << "a dense heap: several pairs per box";
    for (std::size_t threads : {1u, 3u}) {
      WorkerPool pool(threads);
      SweepScratch scratch;
      std::vector<BodyPair> pairs;
      EXPECT_TRUE(find_pairs(b.boxes, b.active, b.candidate, b.awake, 1, scratch, pairs,
                             pair_budget(b.boxes.size()), pool));
      EXPECT_EQ(pairs, expected) << "seed " << seed << ", " << threads << " threads";
    }
  }
}

TEST(BroadPhase, StopsAtTheBudgetWithTheSamePairsForAnyThreadCount) {
  const Boxes b = mixed_boxes(600, 4);
  const std::size_t budget = all_pairs(b).size() / 3;
  std::vector<BodyPair> first;
  for (std::size_t threads : {1u, 2u, 3u}) {
    WorkerPool pool(threads);
    SweepScratch scratch;
    std::vector<BodyPair> pairs;
    EXPECT_FALSE(find_pairs(b.boxes, b.active, b.candidate, b.awake, 1, scratch, pairs, budget,
                            pool));
    EXPECT_EQ(pairs.size(), budget);
    if (threads == 1) first = pairs;
    EXPECT_EQ(pairs, first) << threads << " threads";
  }
}

TEST(BroadPhase, BoxesWithoutFiniteCornersMeetNothing) {
  Boxes b = mixed_boxes(50, 5);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  b.boxes[b.awake[0]].hi.x() = nan;  // a candidate the caller should have dropped: no pairs
  WorkerPool pool(1);
  SweepScratch scratch;
  std::vector<BodyPair> pairs;
  find_pairs(b.boxes, b.active, b.candidate, b.awake, 1, scratch, pairs, 10000, pool);
  for (const BodyPair& p : pairs) EXPECT_TRUE(p.first != b.awake[0] && p.second != b.awake[0]);
}

}  // namespace
}  // namespace tumble
