#pragma once
/// The eight questions tumble-bench answers; each writes CSV, plots and its docs section into
/// Options::out. Single-threaded.
#include "common.hpp"

namespace tumble_bench {

/// Error against CPU time per integrator and TOI method on `tumble`, `bounce` and `seed`.
void run_work_precision(const Options& o);
/// Stress tests with pass criteria (long runs, fast spin, thin plate, rest, Zeno, masses,
/// one long step).
void run_stability(const Options& o);
/// ns per body-step and peak memory for N separated falling boxes.
void run_throughput(const Options& o);
/// Cost of 10,000 resting + 10 falling boxes against the 10 alone.
void run_skip(const Options& o);
/// The same scenes on Bullet, ODE, MuJoCo (and Box3D when built beside), interleaved with
/// Tumble; ratios.
void run_peers(const Options& o);
/// Box–box contact and stacking (tower, pyramid, pile) on Tumble and the peers, interleaved.
void run_contact(const Options& o);
/// `pile`'s deepest overlap against CPU time per simulated second, dt 1/60 … 1/480, every engine.
void run_pile_precision(const Options& o);
/// Where the time of a step goes, per engine stage (tower, pyramid, pile, throughput, landing).
void run_stages(const Options& o);

}  // namespace tumble_bench
