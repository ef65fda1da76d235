#pragma once
/// contact: box–box contact and stacking on Tumble and on the peers, interleaved in one run.
/// Split in three: measure (plain structs, no files), record (CSV, headline values, plot),
/// report (the Markdown section from bench/text/contact.md). Single-threaded.
#include <cmath>
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "common.hpp"
#include "contenders.hpp"
#include "tumble/scene.hpp"

namespace tumble_bench::contact {

/// One scene of the table and how it is run.
struct SceneSpec {
  std::string name;          ///< Bundled scene ("tower", "pyramid", "pile", "pyramid_large").
  long fixed_timed_steps;    ///< Steps timed; 0: the steps before Tumble first puts a body to
                             ///< sleep (at most timed_cap), the same steps on every engine.
  long timed_cap;            ///< Cap of that search, steps.
  long sleep_cap;            ///< Steps of the untimed run with sleeping.
  int every;                 ///< Penetration sample period of that run, steps.
  double budget;             ///< CPU s of one timed run; an engine needing more stops early.
  double behaviour_budget;   ///< CPU s of one untimed run.
  bool stack;                ///< A stack: report whether its top box stays put.
};

/// The scenes, sizes and budgets for a full run or for --quick.
std::vector<SceneSpec> scene_specs(bool quick);
/// Steps of the tower's kept-awake drift run (60 s at dt = 1/60; fewer with --quick).
long tower_awake_steps(bool quick);

/// Top box of a stack may move at most this far over the run to count as standing, m.
inline constexpr double kStandsTolerance = 0.05;

/// What an untimed run saw.
struct Behaviour {
  double penetration = NAN;  ///< Deepest overlap seen, m.
  double drift = NAN;        ///< Largest |x − x₀| over the bodies at the end, m.
  double top_moved = NAN;    ///< Largest |x − x₀| of the top box over the run, m (stacks).
  double top_left_at = NAN;  ///< Sim time the top box first moved > kStandsTolerance, s.
  double end_time = NAN;     ///< Sim time at the end of the run, s.
  double asleep_at = NAN;    ///< Sim time when every body first slept (NaN: never/no sleeping).
  std::string trouble;       ///< What went wrong in the engine, empty when nothing did.
};

/// One engine on one scene.
struct EngineResult {
  std::vector<double> ms;  ///< CPU ms per step, one per repetition (threaded: wall clock).
  /// Wall-clock ms per step of the same runs: what a threaded run's speed-up compares.
  std::vector<double> wall_ms;
  long steps_done = 0;     ///< Fewest steps timed over the repetitions (CPU budget).
  /// Most timed steps of one repetition run on the calling thread alone (threaded Tumble on a
  /// busy machine; 0 when none, -1 for an engine without the count).
  long steps_alone = -1;
  std::string refused;     ///< Why the engine refused or broke in a timed run, else empty.
  Behaviour tower_awake;   ///< Tower only: 60 s kept awake.
  Behaviour sleeping;      ///< With the engine's own sleeping, until asleep or the cap.
};

/// One scene on every engine.
struct SceneResult {
  SceneSpec spec;                              ///< How it was run.
  std::size_t bodies = 0;                      ///< Bodies in the scene.
  double dt = NAN;                             ///< The scene's step, s.
  long timed_steps = 0;                        ///< Steps timed on every engine.
  std::map<std::string, EngineResult> engine;  ///< By engine name.
};

/// A whole contact run.
struct Measurement {
  std::vector<Contender> engines;    ///< In table order, Tumble first.
  int reps = 1;                      ///< Interleaved repetitions of the timing.
  long tower_steps = 0;              ///< Steps of the tower's kept-awake run.
  std::vector<SceneResult> scenes;   ///< In table order.
};

/// Runs every scene on every engine (timing interleaved by repetition), no files written.
Measurement measure(const Options& o);

/// Deepest penetration (m, ≥ 0) between any two boxes and between any box and the floor,
/// from the poses `w` reports (15-axis separating-axis depth), for the boxes of `s`.
double deepest_penetration(const PeerWorld& w, const tumble::Scene& s);

/// One row of the table, derived from a SceneResult (shared by the CSV and the Markdown).
struct Row {
  std::string scene;          ///< Scene name.
  std::string engine;         ///< Engine name.
  double ms = NAN;            ///< Median ms per step (NaN unless valid, Tumble always).
  double ratio = NAN;         ///< Peer time / Tumble time (1 for Tumble).
  double tower_drift = NAN;   ///< m, tower only.
  double penetration = NAN;   ///< m.
  double top_moved = NAN;     ///< m, stacks only.
  std::string stands;         ///< "yes", "no (from t s)", or "–" (not a stack / not run).
  std::string asleep;         ///< "0.8 s", "> 10 s", "no sleeping", "–".
  std::string note;           ///< Refusal or trouble, else the short-timing note.
  bool valid = false;         ///< Ran and nothing went wrong.
};


/// The table rows of one scene, engines in order.
std::vector<Row> rows(const Measurement& m, const SceneResult& r);

/// Writes contact.csv, the headline values and the plot; returns the SVG path.
fs::path record(const Options& o, const Measurement& m);

/// Writes the `contact` section (bench/text/contact.md filled in).
void report(const Options& o, const Measurement& m, const fs::path& svg);

}  // namespace tumble_bench::contact
