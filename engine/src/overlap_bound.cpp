#include "overlap_bound.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "box_box.hpp"

namespace tumble {
namespace {

/// How deep body b's lowest vertex is below the floor at `height`, m (≤ 0: above it).
double floor_depth(const Body& b, double height) {
  const double reach = b.s.R.row(1).cwiseAbs().dot(b.c.half_extents);
  return height - (b.s.x.y() - reach);
}

/// What a pass started from: body i's record then.
class Before {
 public:
  Before(std::span<const std::uint32_t> moved, std::span<const Body> before,
         std::span<const Body> after)
      : moved_(moved), before_(before), after_(after) {}
  /// Body i at the pass's start.
  const Body& operator[](std::uint32_t i) const {
    const auto it = std::lower_bound(moved_.begin(), moved_.end(), i);
    return it != moved_.end() && *it == i ? before_[static_cast<std::size_t>(it - moved_.begin())]
                                          : after_[i];
  }

 private:
  std::span<const std::uint32_t> moved_;
  std::span<const Body> before_, after_;
};

/// Whether a pair or a box on the floor that ends `end` deep (m, > bound) after starting
/// `start` deep broke the bound: it crossed it, or it was past it already (a scene that places
/// boxes inside each other, the last halves kept) and sank a quarter of the bound further.
/// Without that quarter a pair resting just past the bound, whose depth moves by round-off,
/// would halve every pass.
bool broke(double start, double end, double bound) {
  return start <= bound || end > start + 0.25 * bound;
}

/// How deep the pair's boxes end when that broke the bound, else 0. Most pairs end at the
/// bounding spheres or at the first face axis (box_depth stops at `bound`); a pair deeper than
/// the bound went through all 15 axes, so its depth is exact, and only it is measured at the
/// pass's start.
double pair_grown(const Before& before, std::span<const Body> after, const BodyPair& p,
                  double bound) {
  const Body& a = after[p.first];
  const Body& b = after[p.second];
  const double reach = a.c.bounding_radius + b.c.bounding_radius - bound;
  if ((b.s.x - a.s.x).squaredNorm() >= reach * reach && reach > 0.0) return 0.0;
  const double end = box_depth(a.s, a.c, b.s, b.c, bound);
  if (end <= bound) return 0.0;
  const Body& a0 = before[p.first];
  const Body& b0 = before[p.second];
  return broke(box_depth(a0.s, a0.c, b0.s, b0.c, -INFINITY), end, bound) ? end : 0.0;
}

}  // namespace

// A fixed step lets a box fall a whole step's travel into another before the contact that
// should have stopped it is seen (docs/engine.md, "What is left": in `pile` at dt = 1/60,
// up to 14 cm). Rather than a time of impact per pair, the World measures the pass's end and
// takes the pass again in halves where it sank too far, as an adaptive integrator rejects a
// step whose error estimate is over its tolerance (Hairer, Nørsett & Wanner, "Solving
// Ordinary Differential Equations I", §II.4); here the estimate is the overlap itself, exact
// for boxes by the separating axes.
double overlap_grown(std::span<const std::uint32_t> moved, std::span<const Body> before,
                     std::span<const Body> after, std::span<const BodyPair> pairs,
                     const WorldDef& world, double bound, WorkerPool& pool) {
  const Before start(moved, before, after);
  constexpr std::size_t kGrain = 512;  // pairs per chunk: ~20 ns each, most ending early
  std::atomic<double> deepest = 0.0;   // a maximum: the same whatever order the chunks run in
  pool.for_each(pairs.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    double chunk = 0.0;
    for (std::size_t k = begin; k < end; ++k)
      chunk = std::max(chunk, pair_grown(start, after, pairs[k], bound));
    double seen = deepest.load(std::memory_order_relaxed);
    while (chunk > seen && !deepest.compare_exchange_weak(seen, chunk, std::memory_order_relaxed)) {
    }
  });
  double result = deepest.load();
  if (!world.floor) return result;
  const double height = world.floor->height;
  for (std::size_t k = 0; k < moved.size(); ++k) {
    const double end = floor_depth(after[moved[k]], height);
    if (end > bound && broke(floor_depth(before[k], height), end, bound))
      result = std::max(result, end);
  }
  return result;
}

}  // namespace tumble
