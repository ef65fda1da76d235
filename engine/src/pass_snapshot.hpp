#pragma once
/// What World::step keeps to take a pass again under WorldDef::max_overlap (world_step.cpp).
#include <array>
#include <cstdint>
#include <vector>

#include "pipeline.hpp"

namespace tumble {

/// What the rest of a pass can change once its contacts are found, kept to take it again:
/// the awake bodies (the others stay as they are), the contact cache and the pass count.
struct PassSnapshot {
  bool taken = false;                // the pass had pairs to check (else nothing was kept)
  std::vector<std::uint32_t> ids;    // the awake bodies, ascending
  std::vector<Body> bodies;          // their records
  ContactCache cache;
  std::uint64_t passes = 0;
};

/// One snapshot per level of halving, reused from step to step.
struct PassSnapshots {
  std::array<PassSnapshot, kMaxHalvings> levels;
};

}  // namespace tumble
