/// Sweep and prune: the pairs of overlapping boxes (find_pairs, declared in broad_phase.hpp).
/// The broad-phase stage calls it on its fat boxes; initial_pairs on the boxes as placed.
#include <algorithm>
#include <array>
#include <cmath>

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

void add_pair(std::vector<BodyPair>& pairs, std::uint32_t a, std::uint32_t b) {
  pairs.emplace_back(std::min(a, b), std::max(a, b));
}

// Slabs across the sweep. Along one direction the intervals of boxes spread over a plane (a
// floor of 10,000 separated cubes) overlap by the dozen, each box meeting ~60 that are a
// whole grid away in the other direction: O(n √n) tests, 4 ms for each sweep of the 10,000
// cubes. Cut into slabs across the sweep (along kAcross, in the floor's plane and square to
// the sweep) each box meets only those of its own slabs. A box is listed in every slab it
// reaches, and a pair is reported only in the first slab that holds both, so once. (One
// sweep per region of space is Bullet's multi-SAP; Tracy, Buss & Woods 2009, "Efficient
// large-scale sweep and prune methods with AABB insertion and removal", discuss it.)
const Vec3 kAcross = kSweep.cross(Vec3::UnitY()).normalized();
constexpr double kSweepBodyCost = 16.0;   // a body's share of a sweep, in overlap tests
constexpr std::size_t kMinSlabBodies = 256;  // fewer awake boxes: one slab
constexpr double kMaxListings = 3.0;      // slab listings per box, on average, at most

/// The slab (of `count`) that the point x across the sweep falls in.
std::size_t slab_of(const SweepScratch& scratch, std::size_t count, double x) {
  if (count == 1 || !(x > scratch.slab_base)) return 0;
  const double s = (x - scratch.slab_base) / scratch.slab_width;
  return s >= static_cast<double>(count - 1) ? count - 1 : static_cast<std::size_t>(s);
}

/// Where a box lies across the sweep: [lo, hi], m.
std::pair<double, double> across_of(const Aabb& b) {
  const double c = (0.5 * (b.lo + b.hi)).dot(kAcross);
  const double h = (0.5 * (b.hi - b.lo)).dot(kAcross.cwiseAbs());
  return {c - h, c + h};
}

/// Puts the awake boxes (scratch.awake, in sweep order) into slabs about twice as wide as
/// the average box across the sweep, each slab in sweep order (scratch.slab_offset,
/// slab_items). One slab when the boxes are few or lie along the sweep.
void build_slabs(SweepScratch& scratch, std::span<const Aabb> boxes) {
  const std::vector<std::uint32_t>& awake = scratch.awake;
  const std::size_t m = awake.size();
  scratch.across.resize(m);
  double lo = INFINITY, hi = -INFINITY, widths = 0.0;
  for (std::size_t k = 0; k < m; ++k) {
    scratch.across[k] = across_of(boxes[awake[k]]);
    lo = std::min(lo, scratch.across[k].first);
    hi = std::max(hi, scratch.across[k].second);
    widths += scratch.across[k].second - scratch.across[k].first;
  }
  double width = m > 0 ? 2.0 * widths / static_cast<double>(m) : 0.0;
  std::size_t count = 1;
  scratch.slab_base = lo;
  if (m >= kMinSlabBodies && width > 0.0 && std::isfinite(hi - lo)) {
    for (;; width *= 2.0) {  // wider slabs until the listings are few (a few huge boxes)
      const double slabs = std::floor((hi - lo) / width) + 1.0;
      count = slabs < static_cast<double>(m / 4) ? static_cast<std::size_t>(slabs) : m / 4;
      if (count <= 1) break;
      scratch.slab_width = width;
      double listings = 0.0;
      for (const auto& [a, b] : scratch.across)
        listings += static_cast<double>(slab_of(scratch, count, b) - slab_of(scratch, count, a) + 1);
      if (listings <= kMaxListings * static_cast<double>(m)) break;
    }
  }
  count = std::max<std::size_t>(count, 1);
  scratch.slab_width = count == 1 ? 0.0 : width;
  auto first_of = [&](std::size_t k) { return slab_of(scratch, count, scratch.across[k].first); };
  auto last_of = [&](std::size_t k) { return slab_of(scratch, count, scratch.across[k].second); };
  std::vector<std::uint32_t>& offset = scratch.slab_offset;
  offset.assign(count + 1, 0);
  for (std::size_t k = 0; k < m; ++k)
    for (std::size_t s = first_of(k), e = last_of(k); s <= e; ++s) ++offset[s + 1];
  for (std::size_t s = 1; s <= count; ++s) offset[s] += offset[s - 1];
  scratch.slab_items.resize(offset[count]);
  for (std::size_t k = 0; k < m; ++k) {
    const Aabb& b = boxes[awake[k]];
    const std::size_t first = first_of(k);
    const SlabItem item{b, scratch.start[awake[k]], interval_end(b), awake[k],
                        static_cast<std::uint32_t>(first)};
    for (std::size_t s = first, e = last_of(k); s <= e; ++s) scratch.slab_items[offset[s]++] = item;
  }
  for (std::size_t s = count; s > 0; --s) offset[s] = offset[s - 1];  // ends back to starts
  offset[0] = 0;
}

/// The awake pairs of slab items [first, last) (each with the items after it in its slab),
/// appended to `out`; stops once `out` holds more than max_pairs. Ranges of items, not of
/// slabs, so that threads share the work when there are few slabs. Returns the number of
/// overlap tests.
std::size_t sweep_slabs(const SweepScratch& scratch, std::size_t first, std::size_t last,
                        std::vector<BodyPair>& out, std::size_t max_pairs) {
  std::size_t tests = 0;
  const std::vector<SlabItem>& items = scratch.slab_items;
  const std::vector<std::uint32_t>& offset = scratch.slab_offset;
  std::size_t s = static_cast<std::size_t>(
      std::upper_bound(offset.begin(), offset.end(), first) - offset.begin() - 1);
  // Each partner found goes into `hits` and the count moves on only for those that overlap:
  // no branch on the test, which a pile's sweep takes at random for one test in five or six.
  constexpr std::size_t kHits = 64;
  std::array<std::uint32_t, kHits> hits;
  for (std::size_t i = first; i < last && out.size() <= max_pairs; ++i) {
    while (i >= offset[s + 1]) ++s;
    const SlabItem& a = items[i];
    const std::size_t end = offset[s + 1];
    std::size_t found = 0;
    for (std::size_t j = i + 1; j < end && items[j].start <= a.end; ++j) {
      ++tests;
      const SlabItem& b = items[j];
      hits[found] = b.id;
      found += int{overlaps(a.box, b.box)} & int{std::max(a.first, b.first) == s};
      if (found == kHits) {
        for (std::uint32_t id : hits) add_pair(out, a.id, id);
        found = 0;
      }
    }
    for (std::size_t h = 0; h < found; ++h) add_pair(out, a.id, hits[h]);
  }
  return tests;
}

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

/// The sweep order of bodies: by interval start, then by index (a strict total order, so every
/// sort gives the same list).
auto by_start(const std::vector<double>& start) {
  return [&start](std::uint32_t a, std::uint32_t b) {
    return start[a] < start[b] || (start[a] == start[b] && a < b);
  };
}

/// Keeps `list` = the bodies with flag set, sorted by start (insertion sort from last order).
void sort_by_start(std::vector<std::uint32_t>& list, const std::vector<double>& start) {
  const auto less = by_start(start);
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

/// The pairs of awake[first, last) with the sleeping bodies, appended to `out`; stops once
/// `out` holds more than max_pairs. Returns the number of overlap tests.
std::size_t sweep_sleeping(const SweepScratch& scratch, std::span<const Aabb> boxes,
                           std::size_t first, std::size_t last, std::vector<BodyPair>& out,
                           std::size_t max_pairs) {
  std::size_t tests = 0;
  const std::vector<std::uint32_t>& awake = scratch.awake;
  const std::vector<std::uint32_t>& sleeping = scratch.sleeping;
  if (sleeping.empty()) return 0;
  for (std::size_t i = first; i < last && out.size() <= max_pairs; ++i) {
    const std::uint32_t a = awake[i];
    const Aabb& ba = boxes[a];
    const double end = interval_end(ba);
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

/// The awake candidates in sweep order (scratch.awake, scratch.start, scratch.awake_width):
/// last step's order for the bodies still awake, then the rest appended, sorted again by
/// insertion (almost sorted: bodies move little between steps) or, after many newcomers (the
/// first step, a mass wake-up), in full.
void order_awake(std::span<const Aabb> boxes, std::span<const std::uint8_t> active,
                 std::span<const std::uint8_t> candidate,
                 std::span<const std::uint32_t> awake_ids, SweepScratch& scratch) {
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
    std::sort(awake.begin(), awake.end(), by_start(scratch.start));
  } else {
    sort_by_start(awake, scratch.start);
  }
}

/// The sleeping candidates in sweep order (scratch.sleeping, sleeping_width), sorted again
/// only when their set has changed (sleeping_key).
void order_sleeping(std::span<const Aabb> boxes, std::span<const std::uint8_t> active,
                    std::span<const std::uint8_t> candidate, std::uint64_t sleeping_key,
                    SweepScratch& scratch) {
  if (sleeping_key == scratch.sleeping_signature) return;
  scratch.sleeping.clear();
  scratch.sleeping_width = 0.0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (!candidate[i] || active[i]) continue;
    scratch.start[i] = interval_start(boxes[i]);
    scratch.sleeping.push_back(static_cast<std::uint32_t>(i));
    scratch.sleeping_width =
        std::max(scratch.sleeping_width, interval_end(boxes[i]) - scratch.start[i]);
  }
  std::sort(scratch.sleeping.begin(), scratch.sleeping.end(), by_start(scratch.start));
  scratch.sleeping_signature = sleeping_key;
}

/// The awake pairs slab by slab, then the pairs with sleeping bodies in sweep order, into
/// `pairs`: shared among the pool's threads in fixed ranges of each, each range with its own
/// list; joined in range order they are the pairs of the two loops in order, whatever the
/// thread count. One thread sweeps straight into `pairs`: no ranges to join. Counts the
/// sweep's cost (scratch.tests, swept).
void sweep_pairs(std::span<const Aabb> boxes, SweepScratch& scratch,
                 std::vector<BodyPair>& pairs, std::size_t max_pairs, WorkerPool& pool) {
  const std::vector<std::uint32_t>& awake = scratch.awake;
  const std::size_t items = scratch.slab_items.size();
  const std::size_t ranges =
      pool.size() == 1 ? 1 : std::min<std::size_t>(4 * pool.size(), awake.size() / 64 + 1);
  scratch.range_pairs.resize(2 * ranges);
  scratch.range_tests.resize(2 * ranges);
  auto sweep_ranges = [&](std::size_t begin, std::size_t end) {
    for (std::size_t r = begin; r < end; ++r) {
      std::vector<BodyPair>& out = ranges == 1 ? pairs : scratch.range_pairs[r];
      if (ranges > 1) out.clear();
      const std::size_t q = r % ranges;
      scratch.range_tests[r] =
          r < ranges ? sweep_slabs(scratch, items * q / ranges, items * (q + 1) / ranges, out,
                                   max_pairs)
                     : sweep_sleeping(scratch, boxes, awake.size() * q / ranges,
                                      awake.size() * (q + 1) / ranges, out, max_pairs);
    }
  };
  if (ranges == 1)
    sweep_ranges(0, 2);
  else
    pool.for_each(2 * ranges, 1, [&](std::size_t b, std::size_t e) { sweep_ranges(b, e); });
  scratch.tests = static_cast<std::size_t>(kSweepBodyCost * static_cast<double>(awake.size()));
  for (std::size_t t : scratch.range_tests) scratch.tests += t;
  scratch.swept = awake.size();
  if (ranges > 1)
    for (const std::vector<BodyPair>& part : scratch.range_pairs)
      pairs.insert(pairs.end(), part.begin(), part.end());
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
  order_awake(boxes, active, candidate, awake_ids, scratch);
  order_sleeping(boxes, active, candidate, sleeping_key, scratch);
  build_slabs(scratch, boxes);
  sweep_pairs(boxes, scratch, pairs, max_pairs, pool);
  const bool complete = pairs.size() <= max_pairs;  // a range stops only past max_pairs
  if (pairs.size() > max_pairs) pairs.resize(max_pairs);
  sort_pairs(pairs, boxes.size(), scratch);
  return complete;
}

// The sweep's slabs and sleeping order answer a query for one box: its interval along the
// sweep direction can meet only those that start at most the widest interval before it. A body that
// leaves its fat box between sweeps is paired this way in about the tests the sweep made for
// it, where testing it against every body cost n (3.5 % of a fall of 10,000 cubes).
std::size_t boxes_near(const SweepScratch& scratch, std::span<const Aabb> boxes, const Aabb& box,
                       std::vector<std::uint32_t>& out) {
  const std::size_t count = scratch.slab_offset.size() - 1;
  const auto [lo, hi] = across_of(box);
  const double from = interval_start(box) - scratch.awake_width, to = interval_end(box);
  std::size_t tests = 0;
  const std::vector<SlabItem>& items = scratch.slab_items;
  const std::size_t first = slab_of(scratch, count, lo), last = slab_of(scratch, count, hi);
  for (std::size_t s = first; s <= last; ++s) {
    const auto begin = items.begin() + scratch.slab_offset[s];
    const auto end = items.begin() + scratch.slab_offset[s + 1];
    auto it = std::lower_bound(begin, end, from,
                               [](const SlabItem& item, double v) { return item.start < v; });
    for (; it != end && it->start <= to; ++it, ++tests)
      if (std::max<std::size_t>(it->first, first) == s && overlaps(box, boxes[it->id]))
        out.push_back(it->id);  // in the first slab that holds both, so once
  }
  return tests + near_in(scratch.sleeping, scratch.start, scratch.sleeping_width, boxes, box, out);
}

}  // namespace tumble
