#pragma once
/// The check behind WorldDef::max_overlap: whether one pass of a step let two boxes, or a box
/// and the floor, sink into each other deeper than the bound and deeper than they were when
/// the pass began. World::step takes such a pass again as two halves (world_step.cpp).
#include <span>

#include "broad_phase.hpp"
#include "tumble/body.hpp"
#include "tumble/scene.hpp"
#include "worker_pool.hpp"

namespace tumble {

/// The deepest overlap, m, of the pairs of `pairs` (ids into `after`) that overlap deeper
/// than `bound` (m, > 0) in `after` and either were within it at the pass's start or are now a
/// quarter of the bound deeper than they were then, and of the bodies `moved` in the floor (if
/// any) by the same rule; 0 when there is none. At the pass's start body moved[k] was
/// before[k] (ids ascending), and every other body was as it is in `after`. Reads only; shares
/// the pairs among pool's threads (the result is the same for any count).
double overlap_grown(std::span<const std::uint32_t> moved, std::span<const Body> before,
                     std::span<const Body> after, std::span<const BodyPair> pairs,
                     const WorldDef& world, double bound, WorkerPool& pool);

}  // namespace tumble
