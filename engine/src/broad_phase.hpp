#pragma once
/// Broad phase: which pairs of bodies may touch during the next step. Sweep and prune on x
/// over axis-aligned bounding boxes fattened by each body's motion. Pure functions over the
/// caller's scratch buffers; thread-safe.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "tumble/body.hpp"

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

/// A candidate pair of body indices, first < second.
using BodyPair = std::pair<std::uint32_t, std::uint32_t>;

/// Every pair whose boxes overlap and of which at least one body is `active` (sleeping pairs
/// stay asleep), in ascending (first, second) order. `order` is scratch: it keeps the last
/// sort along x, so a scene that moves little re-sorts in about linear time (insertion sort).
/// `candidate[i]` false leaves body i out entirely (frozen bodies).
void find_pairs(std::span<const Aabb> boxes, std::span<const std::uint8_t> active,
                std::span<const std::uint8_t> candidate, std::vector<std::uint32_t>& order,
                std::vector<BodyPair>& pairs);

}  // namespace tumble
