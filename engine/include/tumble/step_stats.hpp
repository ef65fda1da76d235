#pragma once
/// What one World::step did and where its time went: cheap counters for benchmarks, metrics
/// and the per-stage breakdown in docs/benchmarks.md. Plain data; not synchronised.
#include <array>
#include <cstdint>

namespace tumble {

/// The stages of World::step, in the order they run (engine/src/pipeline.hpp).
enum class Stage : std::uint8_t {
  broad_phase,   ///< Which pairs of bodies may touch (swept boxes, sweep and prune).
  narrow_phase,  ///< Box–box and box–floor manifolds of those pairs; waking touched islands.
  islands,       ///< Bodies linked by contacts; a lone body is an island of one.
  contact_solve, ///< Impacts, friction and non-penetration impulses of the islands.
  flight,        ///< Every awake body moved over dt (lone bodies: the scene's integrator).
  finalize,      ///< Finiteness (freeze) and re-orthonormalisation.
  sleep,         ///< Islands that have been still long enough fall asleep.
};

/// Number of stages.
inline constexpr int kStageCount = 7;

/// Short lower-case name of a stage ("broad_phase", …), for tables and CSV columns.
constexpr const char* stage_name(Stage stage) {
  constexpr std::array<const char*, kStageCount> names{
      "broad_phase", "narrow_phase", "islands", "contact_solve", "flight", "finalize", "sleep"};
  return names[static_cast<int>(stage)];
}

/// What the last step did (cheap counters, for benchmarks and metrics).
struct StepStats {
  std::uint32_t impacts = 0;         ///< Impacts resolved (floor and body–body).
  std::uint32_t toi_iterations = 0;  ///< Trajectory evaluations spent finding impacts.
  std::uint32_t awake = 0;           ///< Bodies integrated.
  std::uint32_t newly_frozen = 0;    ///< Bodies that went non-finite this step.
  std::uint32_t pairs = 0;           ///< Broad-phase pairs whose bounding boxes overlap.
  std::uint32_t contacts = 0;        ///< Body–body contacts (pairs with manifold points).
  std::uint32_t contact_points = 0;  ///< Points in those contacts.
  std::uint32_t islands = 0;         ///< Islands of touching bodies solved together.
  std::uint32_t solver_bodies = 0;   ///< Bodies stepped by the contact solver.
  std::uint32_t colours = 0;         ///< Colours the contacts were swept by (0: contact order).
  /// 1 when the broad phase stopped at its pair budget (32 per body + 1,024): bodies packed
  /// into one another beyond it were not tested against each other this step.
  std::uint32_t pair_budget_exceeded = 0;
  /// Wall time of each stage (steady clock), ns, indexed by Stage.
  std::array<std::uint64_t, kStageCount> stage_ns{};
};

}  // namespace tumble
