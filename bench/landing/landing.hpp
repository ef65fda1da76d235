#pragma once
/// The `landing` measurement shared by throughput (Tumble alone) and peers (every engine,
/// interleaved): N separated unit cubes dropped onto a floor with μ = 1, e = 0
/// (scenes.hpp: landing_cubes), dt = 1/240 s. Plain structs; no files. Single-threaded.
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "contenders.hpp"

namespace tumble_bench::landing {

/// How long a landing run lasts.
struct Plan {
  long steps = 480;         ///< Timed steps (2 s at dt = 1/240).
  long head_steps = 120;    ///< The first of them timed apart too (0.5 s: the fall).
  long settle_steps = 960;  ///< Untimed steps after the timed ones, at most, looking for the
                            ///< moment every box is asleep (0: don't look past the run).
};

/// Sim time a run covers at most, timed and settling, s (dt: the scene's step).
double watched_until(const Plan& p, double dt);

/// The plan for a full run (2 s, first 0.5 s, settle up to 4 s) or for --quick.
Plan plan(bool quick);
/// Sizes N measured (1,000 and 10,000; smaller with --quick).
std::vector<std::size_t> sizes(bool quick);

/// One landing run of one engine.
struct Run {
  double ns_per_body_step = NAN;       ///< CPU, whole timed run.
  double ns_per_body_step_head = NAN;  ///< CPU, first head_steps.
  double impacts_per_box = NAN;        ///< Impacts over the timed run / N; NaN: no counter.
  double asleep_fraction = NAN;        ///< Boxes asleep at the end of the timed run; NaN: the
                                       ///< engine cannot say or has no sleeping.
  double all_asleep_at = NAN;          ///< Sim time when every box first slept, s; NaN: not
                                       ///< within the run (+ settle), or no sleeping.
  double watched_until = NAN;          ///< Sim time the run (+ settle) covered, s.
  std::string trouble;                 ///< Refusal or trouble; empty when it ran cleanly.
};

/// Builds `c` on `s` (untimed) and runs the plan; `settle`: also look past the timed run for
/// the moment every box is asleep (untimed; the behaviour does not change between
/// repetitions, so callers settle once).
Run run(const Contender& c, const tumble::Scene& s, const Plan& p, bool settle);

}  // namespace tumble_bench::landing
