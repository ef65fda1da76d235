#include "broad_phase.hpp"

#include <algorithm>

namespace tumble {

Aabb swept_aabb(const BodyState& s, const BodyConstants& c, const Vec3& gravity, double dt,
                double margin) {
  // Half extents of the rotated box along the world axes: Σ_k |R_ik| h_k.
  const Vec3 half = s.R.cwiseAbs() * c.half_extents;
  double reach = margin;
  if (dt > 0.0) {
    const Vec3 w = angular_velocity(s, c);
    reach += dt * (s.P.norm() * c.inv_mass + w.norm() * c.bounding_radius) +
             0.5 * dt * dt * gravity.norm();
  }
  const Vec3 grow = half.array() + reach;
  return {s.x - grow, s.x + grow};
}

// Sweep and prune (Baraff 1992, "Dynamic simulation of non-penetrating rigid bodies", §7.4;
// Ericson, Real-Time Collision Detection, §7.5.1): sort the boxes by their lower x bound and
// sweep, testing each box only against those whose x interval is still open. Bodies move
// little between steps, so the previous order is almost sorted and insertion sort is about
// linear; a scene whose boxes never overlap finds no pair and the narrow phase never runs.
void find_pairs(std::span<const Aabb> boxes, std::span<const std::uint8_t> active,
                std::span<const std::uint8_t> candidate, std::vector<std::uint32_t>& order,
                std::vector<BodyPair>& pairs) {
  pairs.clear();
  const std::size_t n = boxes.size();
  if (order.size() != n) {
    order.resize(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::uint32_t>(i);
  }
  auto less = [&](std::uint32_t a, std::uint32_t b) {
    const double la = boxes[a].lo.x(), lb = boxes[b].lo.x();
    return la < lb || (la == lb && a < b);
  };
  for (std::size_t i = 1; i < n; ++i) {
    const std::uint32_t key = order[i];
    std::size_t j = i;
    while (j > 0 && less(key, order[j - 1])) {
      order[j] = order[j - 1];
      --j;
    }
    order[j] = key;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t a = order[i];
    if (!candidate[a]) continue;
    const Aabb& ba = boxes[a];
    for (std::size_t j = i + 1; j < n; ++j) {
      const std::uint32_t b = order[j];
      const Aabb& bb = boxes[b];
      if (bb.lo.x() > ba.hi.x()) break;
      if (!candidate[b] || !(active[a] || active[b])) continue;
      if (bb.lo.y() > ba.hi.y() || ba.lo.y() > bb.hi.y() || bb.lo.z() > ba.hi.z() ||
          ba.lo.z() > bb.hi.z())
        continue;
      pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(pairs.begin(), pairs.end());
}

}  // namespace tumble
