#pragma once
/// The World's body–body contact stages: broad phase, narrow phase and waking (find), then
/// the contact solve and island sleeping (step). They run only when two bodies can touch.
/// Not thread-safe: the World's owner thread alone calls them.
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include "broad_phase.hpp"
#include "contact_solver.hpp"
#include "islands.hpp"
#include "tumble/scene.hpp"
#include "tumble/world.hpp"

namespace tumble {

/// What the contact stages keep between steps, and their scratch buffers.
struct ContactState {
  // Between steps.
  std::vector<std::uint32_t> sleep_next;  ///< Ring of each sleeping island (self when alone).
  std::vector<Contact> previous;          ///< Last step's contacts (for warm starting).
  std::unordered_map<std::uint64_t, std::uint32_t> previous_index;  ///< Pair key → previous.
  SweepScratch sweep;                     ///< Sweep-and-prune orders kept between steps.
  // Per step.
  std::vector<Aabb> boxes;
  std::vector<std::uint8_t> active, candidate, in_solver;
  std::vector<std::uint8_t> box_cached;  ///< boxes[i] is a sleeping body's, still valid.
  std::vector<Aabb> fat;                 ///< Boxes the cached pairs were found for.
  std::vector<BodyPair> fat_pairs;       ///< Pairs of overlapping fat boxes.
  std::uint64_t fat_signature = 0;       ///< Activity flags the fat pairs were found for.
  std::vector<BodyPair> pairs, links;
  std::vector<Contact> contacts;
  std::vector<std::vector<std::uint32_t>> islands;
  std::vector<std::uint32_t> solver_bodies;
  std::vector<BodyState> before;
  std::vector<double> reach;  ///< Fastest neighbour of each body, m/s.
  std::vector<std::int32_t> island_of, solver_index;
  UnionFind sets;
  SolverSettings settings;
};

/// Sets up the state for `body_count` bodies, all awake and alone.
void init_contact_state(ContactState& k, std::size_t body_count);

/// Wakes body id and every body of its sleeping island.
void wake_island(ContactState& k, std::span<Body> bodies, std::uint32_t id);

/// Stage: finds the contacts of the coming step (broad phase over the bodies' swept boxes,
/// box–box narrow phase, waking sleeping islands that are touched) and marks the bodies the
/// contact solver will step (k.in_solver). Returns false, having done nothing else, when no
/// two bodies can touch: then every body takes the floor-only path unchanged.
bool find_contacts(ContactState& k, std::span<Body> bodies, const WorldDef& world, double dt,
                   StepStats& stats);

/// Stage: steps the marked bodies with the contact solver (their floor contacts included),
/// checks finiteness, and puts islands that have been still long enough to sleep.
void step_contacts(ContactState& k, std::span<Body> bodies, const WorldDef& world, double dt,
                   bool renormalize, StepStats& stats);

/// Puts body id to sleep alone (the floor-only path's rule).
inline void sleep_alone(ContactState& k, std::uint32_t id) { k.sleep_next[id] = id; }

}  // namespace tumble
