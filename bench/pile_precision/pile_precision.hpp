#pragma once
/// pile-precision: the `pile` scene's deepest overlap against the run time that buys it, on
/// Tumble and the peers, at dt = 1/60 … 1/480 (contact's work–precision). Split in three:
/// measure (plain structs, no files), record (CSV, headline values, plot), report (the
/// Markdown section from bench/text/pile_precision.md). Single-threaded.
#include <string>
#include <vector>

#include "common.hpp"

namespace tumble_bench::pile_precision {

/// The overlap the question asks about: the engine issue's bound for `pile`, m.
inline constexpr double kBound = 0.01;
/// Tumble with the scene's max_overlap set to kBound, as a contender of its own.
inline constexpr const char* kBoundedName = "tumble-bounded";

/// One engine at one step size: `pile` from its start for the measured interval.
struct Point {
  std::string engine;         ///< Contender name.
  double dt = 0.0;            ///< Step, s.
  long steps = 0;             ///< Steps run (fewer than planned when the CPU budget ran out).
  double cpu_per_sim_s = 0.0; ///< CPU s of the stepping per simulated second.
  double deepest = 0.0;       ///< Deepest box–box or box–floor overlap after any step, m.
  double deepest_at = 0.0;    ///< Sim time of that step, s.
  double time_over = 0.0;     ///< Sim time with some overlap deeper than kBound, s.
  std::string trouble;        ///< Why the engine refused or broke, else empty.
};

/// A whole run.
struct Measurement {
  double duration = 0.0;          ///< Simulated interval of every run, s.
  double budget = 0.0;            ///< CPU s one run may take before it stops early.
  double initial = 0.0;           ///< The scene's own deepest overlap at t = 0, m.
  std::vector<double> dts;        ///< Step sizes, largest first.
  std::vector<std::string> engines;  ///< In table order, Tumble first.
  std::vector<Point> points;      ///< By step size, then engine (the order they ran in).
};

/// Runs every engine at every step size, interleaved (each dt runs every engine in turn).
Measurement measure(const Options& o);

/// An engine's CPU s per simulated second at overlap `depth` (m): log–log interpolation
/// between the two step sizes whose deepest overlaps bracket it, first crossing from the
/// largest dt. NaN when the engine stays deeper at every dt measured; its cost at the largest
/// dt (an upper bound, *at_most set) when it is already within `depth` there.
double cpu_at_depth(const Measurement& m, const std::string& engine, double depth,
                    bool* at_most);

/// Writes pile_precision.csv, the headline values and the plot; returns the SVG path.
fs::path record(const Options& o, const Measurement& m);

/// Writes the `pile_precision` section (bench/text/pile_precision.md filled in).
void report(const Options& o, const Measurement& m, const fs::path& svg);

}  // namespace tumble_bench::pile_precision
