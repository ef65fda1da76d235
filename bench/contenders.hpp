#pragma once
/// The engines a comparison runs: Tumble behind the peers' interface plus every peer found at
/// build time, so that every benchmark drives them all with the same loop. Not thread-safe.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "peers/peer.hpp"
#include "tumble/scene.hpp"

namespace tumble_bench {

/// How a comparison wants a peer built (Tumble takes the scene as it is).
struct PeerSetup {
  bool stacking = false;    ///< Bodies rest on each other: peers add their stacking settings.
  bool allow_sleep = true;  ///< false: peers built with sleeping off (a kept-awake run).
};

/// One engine under test: Tumble or a peer, built from the same tumble::Scene.
struct Contender {
  std::string name;  ///< "tumble", "bullet", "ode", "mujoco", "mujoco-rk4".
  /// Builds a world; throws (std::exception) when the engine refuses the scene.
  std::function<std::unique_ptr<PeerWorld>(const tumble::Scene&, const PeerSetup&)> make;
  std::string keep_awake_note;  ///< How a kept-awake run keeps it awake, in words.
  bool sleeps = true;           ///< false: the engine has no sleeping (MuJoCo 2.2).
  /// Threads a Tumble world steps on (World::set_threads). Above 1 the engine's work runs on
  /// several threads, so a timing takes the wall clock instead of this thread's CPU time.
  unsigned threads = 1;
};

/// Tumble first (on one thread, then as "tumble-<n>t" on `tumble_threads` threads when that is
/// above 1), then the peers found at build time; `with_rk4` adds MuJoCo with RK4.
std::vector<Contender> contenders(bool with_rk4 = false, unsigned tumble_threads = 1);

/// Seconds to charge a timing of `c` from now: this thread's CPU time, or the wall clock for
/// a multi-threaded contender.
double clock_of(const Contender& c);

/// CPU seconds of `steps` steps of a fresh world (building it is not timed); NaN when the
/// engine refused the scene (*why, if given, says why).
double timed_run(const Contender& c, const tumble::Scene& s, long steps,
                 std::unique_ptr<PeerWorld>* keep = nullptr, std::string* why = nullptr);

}  // namespace tumble_bench
