#pragma once
/// peers: the same scenes on Bullet, ODE, MuJoCo and Box3D (those found at build time),
/// interleaved with Tumble in one run: `tumble` at many dt, `bounce` apexes, throughput at
/// N = 1,000 and 10,000, `skip`, and the `landing` variant (unit cubes onto a floor with μ = 1,
/// e = 0).
/// Split in measure (plain structs), record (CSV, headline values, plots) and report
/// (bench/text/peers.md). The adapters themselves are peer.hpp and bullet/ode/mujoco/box3d.cpp.
#include <cmath>
#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common.hpp"
#include "contenders.hpp"
#include "landing/landing.hpp"
#include "scenes.hpp"

namespace tumble_bench::peers {

/// One engine at one dt on the `tumble` scene.
struct TumbleRun {
  std::string engine;  ///< Engine name.
  double dt = NAN;   ///< s.
  double cpu = NAN;  ///< CPU s of the whole 20 s run.
  double err = NAN;  ///< Geodesic orientation error at 20 s against the reference, rad.
};

/// The first three apexes of `bounce` on one engine.
struct BounceRun {
  std::string engine;                ///< Engine name.
  double apex[3] = {NAN, NAN, NAN};  ///< m (lowest point of the cube).
  double err = NAN;                  ///< |apex 1 − e²h₀|, m.
};

/// (N, shape) of a throughput scene.
using Key = std::pair<std::size_t, BoxShape>;

/// Everything a peers run measured.
struct Measurement {
  std::vector<Contender> all;    ///< Every engine, MuJoCo RK4 included (tumble, bounce).
  std::vector<Contender> fast;   ///< Without MuJoCo RK4 (throughput, skip, landing).
  int reps = 3;                  ///< Interleaved repetitions.
  int tumble_dts = 9;            ///< dt = 1/15 · 2^-k, k < tumble_dts.
  std::vector<TumbleRun> tumble;                 ///< Engine-major, dt decreasing.
  double bounce_h0 = NAN, bounce_e = NAN;        ///< Drop height (lowest point), m; e.
  std::vector<BounceRun> bounce;                 ///< By engine.
  std::vector<std::size_t> sizes;                ///< N of the throughput scenes.
  double duration = 2.0;                         ///< Simulated s of a throughput run.
  long steps = 480;                              ///< Steps of a throughput run.
  std::map<std::string, std::map<Key, std::vector<double>>> ns;  ///< ns per body-step.
  std::size_t resting = 10000;                   ///< Resting boxes of the skip scene.
  long skip_steps = 120;                         ///< Steps of a skip run (dt = 1/60).
  std::map<std::string, std::vector<double>> skip_ms;           ///< ms per step, by engine.
  std::map<std::string, std::string> refused;    ///< "engine scene" → why.
  landing::Plan landing_plan;                    ///< Lengths of the landing runs.
  std::vector<std::size_t> landing_sizes;        ///< N of the landing runs.
  std::map<std::string, std::map<std::size_t, std::vector<landing::Run>>> landing;  ///< By engine, N.
};

/// Runs every part, interleaving the engines; writes nothing.
Measurement measure(const Options& o);

/// One engine's landing at one N, medians, with its ratio to Tumble.
struct LandingRow {
  std::string engine;                          ///< Engine name.
  std::size_t n = 0;                           ///< Cubes.
  double ns = NAN, ns_head = NAN;              ///< ns per body-step: whole run, first part.
  double ratio = NAN, ratio_head = NAN;        ///< Peer time / Tumble time (1 for Tumble).
  double impacts_per_box = NAN;                ///< NaN: the engine has no counter.
  double asleep_fraction = NAN;                ///< NaN: the engine cannot say / no sleeping.
  double all_asleep_at = NAN, watched_until = NAN;  ///< s.
  bool sleeps = true;                          ///< The engine has sleeping at all.
  std::string trouble;                         ///< Refusal or trouble of any run.
};

/// The landing rows, N-major, engines in order (Tumble first).
std::vector<LandingRow> landing_rows(const Measurement& m);

/// Files written by record().
struct Files {
  fs::path tumble_csv;      ///< peers_tumble.csv.
  fs::path tumble_svg;      ///< Its plot.
  fs::path bounce_csv;      ///< peers_bounce.csv.
  fs::path throughput_csv;  ///< peers_throughput.csv (skip is in the Markdown only).
  fs::path throughput_svg;  ///< Its plot.
  fs::path landing_csv;     ///< peers_landing.csv.
};

/// Writes the CSV files, the headline values and the plots.
Files record(const Options& o, const Measurement& m);

/// Writes the `peers` section (bench/text/peers.md filled in).
void report(const Options& o, const Measurement& m, const Files& files);

}  // namespace tumble_bench::peers
