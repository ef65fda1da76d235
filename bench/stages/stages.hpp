#pragma once
/// stages: where the time of World::step goes, per stage (tumble::Stage) and per pass of the
/// contact solve (tumble::SolvePass), on the contact scenes (tower, pyramid, pile, kept awake)
/// and the throughput and landing scenes. Sums World::last_step().stage_ns and solve_pass_ns
/// over the steps and sets them against the measured step time.
/// Split in measure (plain structs), record (stages.csv, headline values) and report
/// (bench/text/stages.md). Single-threaded.
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "common.hpp"
#include "tumble/step_stats.hpp"

namespace tumble_bench::stages {

/// Per-stage time of one scene, medians over the repetitions.
struct SceneStages {
  std::string scene;                     ///< "tower", …, "throughput (10000 cubes)".
  std::size_t bodies = 0;                ///< Bodies in the scene.
  long steps = 0;                        ///< Steps timed per repetition.
  bool kept_awake = false;               ///< Bodies woken every 15 steps (contact scenes).
  double step_us = NAN;                  ///< Wall time of World::step, µs per step (steady
                                         ///< clock, the clock of stage_ns).
  double step_cpu_us = NAN;              ///< CPU time of World::step, µs per step.
  std::array<double, tumble::kStageCount> stage_us{};  ///< µs per step, by tumble::Stage.
  double stage_sum_us = 0.0;             ///< Sum of stage_us.
  /// µs per step of each pass of the contact_solve stage, by tumble::SolvePass.
  std::array<double, tumble::kSolvePassCount> pass_us{};
};

/// A stages run.
struct Measurement {
  int reps = 1;                     ///< Repetitions (median taken), scenes interleaved.
  std::vector<SceneStages> scenes;  ///< In table order.
  bool available = false;           ///< Some stage time is non-zero (the engine fills them).
};

/// Runs every scene; writes nothing.
Measurement measure(const Options& o);

/// Writes stages.csv and the headline values; returns the CSV path.
fs::path record(const Options& o, const Measurement& m);

/// Writes the `stages` section (bench/text/stages.md filled in).
void report(const Options& o, const Measurement& m, const fs::path& csv);

}  // namespace tumble_bench::stages
