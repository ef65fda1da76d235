#pragma once
/// throughput: ns per body-step and peak memory for N separated boxes (cubes and general
/// boxes, runs interleaved), every integrator at one N, and the `landing` variant (unit cubes
/// onto a floor with μ = 1, e = 0). Split in measure (plain structs), record (CSV, headline
/// values, plot) and report (bench/text/throughput.md). Single-threaded.
#include <array>
#include <cmath>
#include <cstddef>
#include <map>
#include <utility>
#include <vector>

#include "common.hpp"
#include "landing/landing.hpp"
#include "scenes.hpp"
#include "tumble/scene.hpp"

namespace tumble_bench::throughput {

/// The two shapes, in the order they alternate.
inline constexpr std::array<BoxShape, 2> kShapes{BoxShape::cube, BoxShape::general};
/// Step of every throughput scene, s.
inline constexpr double kDt = 1.0 / 240.0;

/// Sizes and lengths of a run.
struct Config {
  std::vector<std::size_t> sizes;  ///< N of the scaling sweep.
  double duration = 2.0;           ///< Simulated s per run.
  long steps = 480;                ///< duration / dt.
  double head_duration = 0.5;      ///< First part timed apart, s.
  long head_steps = 120;           ///< head_duration / dt.
  std::size_t n_big = 100000;      ///< N from which only the head is run.
  std::size_t n_integ = 10000;     ///< N of the integrator comparison.
  int reps = 3;                    ///< Interleaved repetitions (at least).
  landing::Plan landing;           ///< Lengths of the landing runs.
  std::vector<std::size_t> landing_sizes;  ///< N of the landing runs.
};

/// The configuration for a full run or --quick.
Config config(const Options& o);

/// One timed run of Tumble on a separated-boxes scene.
struct Run {
  double ns_per_body_step = 0.0;       ///< Whole run.
  double ns_per_body_step_head = 0.0;  ///< First head_steps steps only.
  double awake_fraction = 0.0;         ///< Mean of awake / N over the steps.
  double peak_mb = 0.0;                ///< VmHWM after the run, MB.
  double bytes_per_body = 0.0;         ///< Resident growth from building the world, over N.
};

/// Everything a throughput run measured.
struct Measurement {
  Config cfg;                                                        ///< As run.
  std::map<std::pair<BoxShape, std::size_t>, std::vector<Run>> scaling;  ///< By shape and N.
  std::map<std::pair<BoxShape, tumble::Integrator>, std::vector<double>>
      by_integrator;                                                 ///< ns per body-step.
  std::map<std::size_t, std::vector<landing::Run>> landing;          ///< Tumble, by N.
};

/// Runs the scaling sweep, the integrator comparison and the landing runs; writes nothing.
Measurement measure(const Options& o);

/// Medians of one (shape, N) cell of the scaling sweep.
struct ScalingRow {
  BoxShape shape;            ///< Cube or general box.
  std::size_t n = 0;         ///< Bodies.
  bool full = true;          ///< The whole run was timed (N < n_big), not only its head.
  long steps = 0;            ///< Steps per run.
  std::size_t runs = 0;      ///< Runs taken.
  double ns = NAN;           ///< Median ns per body-step, whole run (NaN unless full).
  double ns_head = NAN;      ///< Median over the first head_duration.
  double ns_awake = NAN;     ///< Median ns per awake body-step (NaN unless full).
  Run last;                  ///< The last run (awake fraction and memory).
};

/// The cells of the scaling sweep, N-major, shapes alternating.
std::vector<ScalingRow> scaling_rows(const Measurement& m);

/// Medians of the landing runs at one N.
struct LandingRow {
  std::size_t n = 0;                    ///< Cubes.
  std::size_t runs = 0;                 ///< Runs taken.
  double ns = NAN, ns_head = NAN;       ///< ns per body-step: whole run, first head.
  double impacts_per_box = NAN;         ///< Over the timed run.
  double asleep_fraction = NAN;         ///< At the end of the timed run.
  double all_asleep_at = NAN;           ///< s, NaN: not within watched_until.
  double watched_until = NAN;           ///< s.
  std::string trouble;                  ///< From any run.
};

/// The landing rows, by N.
std::vector<LandingRow> landing_rows(const Measurement& m);

/// Files written by record().
struct Files {
  fs::path csv;          ///< throughput.csv (scaling and integrators).
  fs::path landing_csv;  ///< throughput_landing.csv.
  fs::path svg;          ///< The scaling plot.
};

/// Writes throughput.csv, throughput_landing.csv, the headline values and the plot.
Files record(const Options& o, const Measurement& m);

/// Writes the `throughput` section (bench/text/throughput.md filled in).
void report(const Options& o, const Measurement& m, const Files& files);

}  // namespace tumble_bench::throughput
