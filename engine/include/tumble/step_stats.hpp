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

/// The passes of the contact_solve stage, in the order they run (engine/src/contact_solve.cpp
/// and contact_solver.cpp).
enum class SolvePass : std::uint8_t {
  cache,              ///< Last step's impulses matched to this step's contacts, and kept.
  setup,              ///< The solver bodies' velocities and, on several threads, the colours.
  rows,               ///< Each contact's rows (Solver::prepare).
  impacts,            ///< The collision pass: exact impulses of fast-approaching points.
  warm_start,         ///< The kept impulses applied to the bodies.
  velocity,           ///< The sequential-impulse sweeps, and their impulses stored.
  shock_propagation,  ///< The ground-up pass with the supports held fixed.
  split_impulse,      ///< The pseudo velocities that remove deep penetration.
  finish,             ///< The end-of-step momenta written back to the bodies.
};

/// Number of contact-solve passes.
inline constexpr int kSolvePassCount = 9;

/// Short lower-case name of a pass ("rows", …), for tables and CSV columns.
constexpr const char* solve_pass_name(SolvePass pass) {
  constexpr std::array<const char*, kSolvePassCount> names{
      "cache",    "setup",             "rows",          "impacts", "warm_start",
      "velocity", "shock_propagation", "split_impulse", "finish"};
  return names[static_cast<int>(pass)];
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
  /// 1 when the step, in a World of several threads, ran on the calling thread alone: a
  /// recent step's threads were held up waiting for a descheduled one (a machine with more
  /// runnable threads than cores; engine/src/solo_policy.hpp). The same results.
  std::uint32_t solo = 0;
  /// Passes of the stages the step ran: 1, more where WorldDef::max_overlap had a pass taken
  /// again as two halves (the counters above are the kept passes'; the times below, all).
  std::uint32_t passes = 0;
  /// Passes taken again as halves because they opened an overlap deeper than max_overlap.
  std::uint32_t halved_passes = 0;
  /// Wall time of each stage (steady clock), ns, indexed by Stage.
  std::array<std::uint64_t, kStageCount> stage_ns{};
  /// Wall time of each pass of the contact_solve stage (steady clock), ns, indexed by
  /// SolvePass; their sum is that stage's time less a few clock reads.
  std::array<std::uint64_t, kSolvePassCount> solve_pass_ns{};
};

}  // namespace tumble
