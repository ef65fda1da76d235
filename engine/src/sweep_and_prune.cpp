/// Sweep and prune: the pairs of overlapping boxes (find_pairs, declared in broad_phase.hpp).
/// The broad-phase stage calls it on its fat boxes; initial_pairs on the boxes as placed.
#include <algorithm>

#include "broad_phase.hpp"
#include "worker_pool.hpp"

namespace tumble {
namespace {

// The sweep runs along a fixed generic direction rather than x: scenes are often laid out on
// a grid in x and z, and along x every box of a column would overlap every other one, so the
// sweep would cost O(n √n). Along an irrational mix of the axes the interval starts of a grid
// are all distinct and each box meets only its true neighbours.
const Vec3 kSweep = Vec3(1.0, 0.1234, 0.6180339887).normalized();

double interval_start(const Aabb& b) {
  const Vec3 c = 0.5 * (b.lo + b.hi), h = 0.5 * (b.hi - b.lo);
  return c.dot(kSweep) - h.dot(kSweep.cwiseAbs());
}

double interval_end(const Aabb& b) {
  const Vec3 c = 0.5 * (b.lo + b.hi), h = 0.5 * (b.hi - b.lo);
  return c.dot(kSweep) + h.dot(kSweep.cwiseAbs());
}

double interval_width(const Aabb& b) { return (b.hi - b.lo).dot(kSweep.cwiseAbs()); }

/// Appends the bodies of `order` (sorted by start, no interval wider than `width`) whose box
/// overlaps `box`; returns the tests made.
std::size_t near_in(const std::vector<std::uint32_t>& order, const std::vector<double>& start,
                    double width, std::span<const Aabb> boxes, const Aabb& box,
                    std::vector<std::uint32_t>& out) {
  const double lo = interval_start(box), hi = interval_end(box);
  auto it = std::lower_bound(order.begin(), order.end(), lo - width,
                             [&](std::uint32_t s, double v) { return start[s] < v; });
  std::size_t tests = 0;
  for (; it != order.end() && start[*it] <= hi; ++it, ++tests)
    if (overlaps(box, boxes[*it])) out.push_back(*it);
  return tests;
}

void add_pair(std::vector<BodyPair>& pairs, std::uint32_t a, std::uint32_t b) {
  pairs.emplace_back(std::min(a, b), std::max(a, b));
}

/// Keeps `list` = the bodies with flag set, sorted by start (insertion sort from last order).
void sort_by_start(std::vector<std::uint32_t>& list, const std::vector<double>& start) {
  auto less = [&](std::uint32_t a, std::uint32_t b) {
    return start[a] < start[b] || (start[a] == start[b] && a < b);
  };
  for (std::size_t i = 1; i < list.size(); ++i) {
    const std::uint32_t key = list[i];
    std::size_t j = i;
    while (j > 0 && less(key, list[j - 1])) {
      list[j] = list[j - 1];
      --j;
    }
    list[j] = key;
  }
}

/// Sorts pairs by (first, second) in O(n + pairs): two counting sorts, on the second body and
/// then, stably, on the first (least significant digit first). std::sort was 64 % of the
/// broad phase of `pile`, which rebuilds its pairs nearly every step while boxes fall; an
/// insertion sort of each body's partners after one counting sort was still a sixth of it
/// (a box in a falling pile has ~24 fat pairs).
void sort_pairs(std::vector<BodyPair>& pairs, std::size_t n, SweepScratch& scratch) {
  std::vector<std::uint32_t>& start = scratch.bucket;
  auto by = [&](auto key, const std::vector<BodyPair>& from, std::vector<BodyPair>& to) {
    start.assign(n + 1, 0);
    for (const BodyPair& p : from) ++start[key(p) + 1];
    for (std::size_t i = 1; i <= n; ++i) start[i] += start[i - 1];
    to.resize(from.size());
    for (const BodyPair& p : from) to[start[key(p)]++] = p;
  };
  by([](const BodyPair& p) { return p.second; }, pairs, scratch.sorted);
  by([](const BodyPair& p) { return p.first; }, scratch.sorted, pairs);
}

/// The sweep for awake[first, last): pairs with the awake bodies after each one and with the
/// sleeping ones, appended to `out`; stops once `out` holds more than max_pairs. Returns the
/// number of overlap tests.
std::size_t sweep_range(const SweepScratch& scratch, std::span<const Aabb> boxes,
                        std::size_t first, std::size_t last, std::vector<BodyPair>& out,
                        std::size_t max_pairs) {
  std::size_t tests = 0;
  const std::vector<std::uint32_t>& awake = scratch.awake;
  const std::vector<std::uint32_t>& sleeping = scratch.sleeping;
  for (std::size_t i = first; i < last && out.size() <= max_pairs; ++i) {
    const std::uint32_t a = awake[i];
    const Aabb& ba = boxes[a];
    const double end = interval_end(ba);
    for (std::size_t j = i + 1; j < awake.size(); ++j) {
      const std::uint32_t b = awake[j];
      if (scratch.start[b] > end) break;
      ++tests;
      if (overlaps(ba, boxes[b])) add_pair(out, a, b);
    }
    // Sleeping boxes whose interval can overlap [start, end]: they start after
    // start − widest and before end.
    auto from = std::lower_bound(sleeping.begin(), sleeping.end(),
                                 scratch.start[a] - scratch.sleeping_width,
                                 [&](std::uint32_t s, double v) { return scratch.start[s] < v; });
    for (auto it = from; it != sleeping.end() && scratch.start[*it] <= end; ++it, ++tests)
      if (overlaps(ba, boxes[*it])) add_pair(out, a, *it);
  }
  return tests;
}

}  // namespace

// Sweep and prune (Baraff 1992, "Dynamic simulation of non-penetrating rigid bodies", §7.4;
// Ericson, Real-Time Collision Detection, §7.5.1): sort the boxes by where their projection
// on the sweep direction starts and sweep, testing each box only against those whose
// interval is still open. Bodies move little between steps, so last step's order is almost
// sorted and insertion sort is about linear. Sleeping bodies do not move: they are sorted
// once per change of the sleeping set, and each awake box finds the sleeping ones it may
// touch by binary search over that list.
bool find_pairs(std::span<const Aabb> boxes, std::span<const std::uint8_t> active,
                std::span<const std::uint8_t> candidate,
                std::span<const std::uint32_t> awake_ids, std::uint64_t sleeping_key,
                SweepScratch& scratch, std::vector<BodyPair>& pairs, std::size_t max_pairs,
                WorkerPool& pool) {
  pairs.clear();
  const std::size_t n = boxes.size();
  scratch.start.resize(n);
  std::size_t awake_count = 0;
  scratch.awake_width = 0.0;
  for (std::uint32_t i : awake_ids) {
    if (!candidate[i]) continue;
    scratch.start[i] = interval_start(boxes[i]);
    scratch.awake_width = std::max(scratch.awake_width, interval_width(boxes[i]));
    ++awake_count;
  }
  // The awake list keeps last step's order for the bodies still awake, then appends the rest.
  std::vector<std::uint32_t>& awake = scratch.awake;
  std::erase_if(awake, [&](std::uint32_t i) { return i >= n || !candidate[i] || !active[i]; });
  const std::size_t kept = awake.size();
  if (kept != awake_count) {
    scratch.listed.assign(n, 0);
    for (std::uint32_t i : awake) scratch.listed[i] = 1;
    for (std::uint32_t i : awake_ids)
      if (candidate[i] && !scratch.listed[i]) awake.push_back(i);
  }
  if (awake.size() - kept > awake.size() / 8) {
    // Many newcomers (the first step, a mass wake-up): a full sort, not insertion.
    std::sort(awake.begin(), awake.end(), [&](std::uint32_t a, std::uint32_t b) {
      return scratch.start[a] < scratch.start[b] || (scratch.start[a] == scratch.start[b] && a < b);
    });
  } else {
    sort_by_start(awake, scratch.start);
  }
  if (sleeping_key != scratch.sleeping_signature) {
    scratch.sleeping.clear();
    scratch.sleeping_width = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!candidate[i] || active[i]) continue;
      scratch.start[i] = interval_start(boxes[i]);
      scratch.sleeping.push_back(static_cast<std::uint32_t>(i));
      scratch.sleeping_width =
          std::max(scratch.sleeping_width, interval_end(boxes[i]) - scratch.start[i]);
    }
    std::sort(scratch.sleeping.begin(), scratch.sleeping.end(),
              [&](std::uint32_t a, std::uint32_t b) {
                return scratch.start[a] < scratch.start[b] ||
                       (scratch.start[a] == scratch.start[b] && a < b);
              });
    scratch.sleeping_signature = sleeping_key;
  }
  // The sweep's outer loop is shared among the pool's threads in fixed ranges, each with its
  // own list; joined in range order they are the pairs of the loop in order.
  // One thread sweeps straight into `pairs`: no ranges to join.
  const std::size_t ranges =
      pool.size() == 1 ? 1 : std::min<std::size_t>(4 * pool.size(), awake.size() / 64 + 1);
  scratch.range_pairs.resize(ranges);
  scratch.range_tests.resize(ranges);
  pool.for_each(ranges, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t r = begin; r < end; ++r) {
      std::vector<BodyPair>& out = ranges == 1 ? pairs : scratch.range_pairs[r];
      if (ranges > 1) out.clear();
      scratch.range_tests[r] = sweep_range(scratch, boxes, awake.size() * r / ranges,
                                           awake.size() * (r + 1) / ranges, out, max_pairs);
    }
  });
  scratch.tests = 0;
  for (std::size_t t : scratch.range_tests) scratch.tests += t;
  scratch.swept = awake.size();
  if (ranges > 1)
    for (const std::vector<BodyPair>& part : scratch.range_pairs)
      pairs.insert(pairs.end(), part.begin(), part.end());
  const bool complete = pairs.size() <= max_pairs;  // a range stops only past max_pairs
  if (pairs.size() > max_pairs) pairs.resize(max_pairs);
  sort_pairs(pairs, n, scratch);
  return complete;
}

// The sweep's two orders answer a query for one box: its interval along the sweep direction
// can meet only those that start at most the order's widest interval before it. A body that
// leaves its fat box between sweeps is paired this way in about the tests the sweep made for
// it, where testing it against every body cost n (3.5 % of a fall of 10,000 cubes).
std::size_t boxes_near(const SweepScratch& scratch, std::span<const Aabb> boxes, const Aabb& box,
                       std::vector<std::uint32_t>& out) {
  return near_in(scratch.awake, scratch.start, scratch.awake_width, boxes, box, out) +
         near_in(scratch.sleeping, scratch.start, scratch.sleeping_width, boxes, box, out);
}

}  // namespace tumble
