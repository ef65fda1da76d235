#pragma once
/// Broad phase: which pairs of bodies may touch during the next step. Sweep and prune along a
/// generic direction over axis-aligned bounding boxes fattened by each body's motion; sleeping
/// bodies sit in a sorted list of their own that only awake bodies query. Pure functions over
/// the caller's scratch buffers; thread-safe.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "tumble/body.hpp"
#include "worker_pool.hpp"

namespace tumble {

/// An axis-aligned box in the world, m.
struct Aabb {
  Vec3 lo = Vec3::Zero();
  Vec3 hi = Vec3::Zero();
};

/// The bounding box of a body now, grown by how far any of its points can move in dt seconds
/// (|v| dt + ½|g| dt² + |ω| r dt) plus `margin` metres on every side. A sleeping body does
/// not move: pass dt = 0.
Aabb swept_aabb(const BodyState& s, const BodyConstants& c, const Vec3& gravity, double dt,
                double margin);

/// A bound under which a body's swept box stays inside its fat box, checked in a few
/// instructions instead of computing the box: while x lies in `core`, |P|² ≤ p2 and |L|² ≤ l2
/// (p2 < 0: no bound, compute the box).
struct QuietBound {
  Aabb core;         ///< Where the centre of mass may be, m.
  double p2 = -1.0;  ///< Largest |P|², (kg·m/s)².
  double l2 = -1.0;  ///< Largest |L|², (kg·m²/s)².
};

/// Whether a body in state s is within its quiet bound q (false when q is none).
inline bool within(const QuietBound& q, const BodyState& s) {
  if (!(s.P.squaredNorm() <= q.p2 && s.L.squaredNorm() <= q.l2)) return false;
  const Vec3& x = s.x;
  return (q.core.lo.array() <= x.array()).all() && (x.array() <= q.core.hi.array()).all();
}

/// Whether two boxes overlap (touching counts).
inline bool overlaps(const Aabb& a, const Aabb& b) {
  // All six comparisons, not the first that fails: in a pile a pair's boxes overlap or not
  // about as often as a coin falls, and each early exit was a mispredicted branch.
  int all = 1;
  for (int i = 0; i < 3; ++i) all &= int{a.lo[i] <= b.hi[i]} & int{b.lo[i] <= a.hi[i]};
  return all != 0;
}

/// A candidate pair of body indices, first < second.
using BodyPair = std::pair<std::uint32_t, std::uint32_t>;

/// An awake box in one slab of the sweep (SweepScratch): a copy, so that the sweep of a slab
/// reads memory in order.
struct SlabItem {
  Aabb box;
  double start = 0.0;       ///< Interval start along the sweep direction, m.
  double end = 0.0;         ///< Interval end, m.
  std::uint32_t id = 0;     ///< Body index.
  std::uint32_t first = 0;  ///< Lowest slab the box is in.
};

/// Scratch kept between steps: the sweep orders of the awake and of the sleeping bodies.
struct SweepScratch {
  std::vector<std::uint32_t> awake;       ///< Awake candidates, sorted by their interval start.
  std::vector<std::uint32_t> sleeping;    ///< Sleeping candidates, sorted likewise.
  std::vector<double> start;              ///< Interval start of each body along the sweep.
  std::uint64_t sleeping_signature = ~0ull;  ///< Which sleeping set `sleeping` was sorted for.
  std::vector<std::uint8_t> listed;       ///< Scratch: body already in `awake`.
  std::vector<std::uint32_t> bucket;      ///< Scratch of the pair sort: bucket ends.
  std::vector<BodyPair> sorted;           ///< Scratch of the pair sort: the sorted pairs.
  double sleeping_width = 0.0;            ///< Widest sleeping interval, m.
  std::vector<std::vector<BodyPair>> range_pairs;  ///< Scratch: pairs of each sweep range.
  std::vector<std::size_t> range_tests;            ///< Scratch: overlap tests of each range.
  std::vector<std::uint32_t> slab_offset;  ///< Scratch: start of each slab in slab_items.
  std::vector<SlabItem> slab_items;         ///< Scratch: the awake boxes, slab by slab.
  std::vector<std::pair<double, double>> across;  ///< Scratch: each awake box across the sweep.
  double slab_base = 0.0;   ///< Where slab 0 starts across the sweep, m.
  double slab_width = 0.0;  ///< Width of a slab across the sweep, m (0: one slab).
  /// The last sweep's cost in overlap tests: the tests it made plus kSweepBodyCost for each
  /// awake body (its fat box, interval, place in the order and slab), for the caller to
  /// weigh against pairing bodies one by one.
  std::size_t tests = 0;
  std::size_t swept = 0;  ///< Awake boxes the last sweep sorted.
  double awake_width = 0.0;  ///< Widest awake interval of the last sweep, m.
};

/// Every pair whose boxes overlap and of which at least one body is `active` (sleeping pairs
/// stay asleep), in ascending (first, second) order. `candidate[i]` false leaves body i out
/// entirely (frozen bodies). `awake_ids` lists the active bodies; `sleeping_key` names the
/// set of sleeping candidates and their boxes: the caller changes it whenever they change. Cost: the awake bodies re-sort in about linear time (insertion
/// sort on last step's order); the sleeping ones are sorted only when their set changes and
/// are found by binary search, so 10,000 sleeping boxes cost nothing per step. Stops after
/// `max_pairs` pairs (a bound on the memory and time one step can take when a scene packs
/// bodies into one another) and returns false then; true when every pair was found. The sweep
/// is shared among the threads of `pool`; the pairs do not depend on their number.
bool find_pairs(std::span<const Aabb> boxes, std::span<const std::uint8_t> active,
                std::span<const std::uint8_t> candidate,
                std::span<const std::uint32_t> awake_ids, std::uint64_t sleeping_key,
                SweepScratch& scratch, std::vector<BodyPair>& pairs, std::size_t max_pairs,
                WorkerPool& pool);

/// Appends to `out` the bodies of the last sweep (its awake slabs and its sleeping order)
/// whose box in `boxes` overlaps `box`; returns the overlap tests made. Each slab the box
/// reaches, and the sleeping order, is searched for the intervals that can meet the box's
/// (binary search, then a scan of that range), by the boxes of that sweep: a body whose box
/// changed since may be missed, and the caller tests those on their own.
std::size_t boxes_near(const SweepScratch& scratch, std::span<const Aabb> boxes, const Aabb& box,
                       std::vector<std::uint32_t>& out);

/// The pair budget of a world of `body_count` bodies: 32 per body plus 1,024. A resting pile
/// has about 7 per body (`pile`: 6,852 pairs for 1,000 bodies at most).
inline std::size_t pair_budget(std::size_t body_count) { return 32 * body_count + 1024; }

}  // namespace tumble
