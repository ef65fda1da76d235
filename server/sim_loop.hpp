#pragma once
/// The simulation thread: it alone owns the tumble::World. It runs a fixed-step real-time
/// loop, runs the commands of I/O threads before each step and publishes an immutable
/// Snapshot after every step and every command.
///
/// Usage:
///   SimLoop sim(tumble::load_scene("seed"), metrics);
///   sim.start();
///   sim.submit({PauseCommand{}, [](CommandResult r) { … }});
///   auto snap = sim.latest();   // any thread
///   sim.stop();
#include <deque>
#include <functional>
#include <optional>
#include <memory>
#include <mutex>
#include <thread>
#include <utility>

#include "commands.hpp"
#include "metrics.hpp"
#include "snapshot.hpp"
#include "tumble/world.hpp"

namespace tumble::server {

/// The latest snapshot, handed from the simulation thread (store) to any thread (load).
/// A mutex held for one shared_ptr copy, not std::atomic<std::shared_ptr>: GCC 12's
/// atomic load releases its internal lock with memory_order_relaxed, so a later store is
/// not ordered after the read — a data race in the C++ memory model, reported by TSan.
class SnapshotSlot {
 public:
  /// The stored snapshot (null before the first store). Thread-safe.
  std::shared_ptr<const Snapshot> load() const {
    std::lock_guard lock(mutex_);
    return value_;
  }
  /// Replaces the snapshot; the old one is released outside the lock. Thread-safe.
  void store(std::shared_ptr<const Snapshot> snapshot) {
    {
      std::lock_guard lock(mutex_);
      value_.swap(snapshot);
    }
  }  // `snapshot` now holds the old one: freed here, after the unlock.

 private:
  mutable std::mutex mutex_;
  std::shared_ptr<const Snapshot> value_;
};

/// The real-time loop around one World. Public members are thread-safe.
class SimLoop {
 public:
  /// Most simulated time (s) the loop catches up in one go; beyond that it drops time and
  /// the real-time factor falls below 1 instead of spiralling.
  static constexpr double kMaxCatchUp = 0.1;
  /// Longest the loop steps (wall time) before it looks at the command queue again.
  static constexpr std::chrono::milliseconds kStepBudget{20};
  /// Fastest linear speed (m/s) an impulse may give a body: a kick past it (that does not
  /// slow the body) is refused with 400, the world untouched.
  static constexpr double kMaxSpeed = 1e3;
  /// Fastest spin (rad/s) an impulse may give a body; the same rule.
  static constexpr double kMaxSpin = 1e3;
  /// Wall-time window (s) over which the real-time factor is measured.
  static constexpr double kRtfWindow = 2.0;
  /// Shortest window (s) that updates it; until then (after a start, resume or reset) the
  /// last value stands (1 at start).
  static constexpr double kRtfMinWindow = 0.05;

  /// Builds the world (throws tumble::InvalidInput for an invalid scene) and publishes its
  /// first snapshot. The loop does not run until start(). Each step runs on `sim_threads`
  /// threads (this loop's thread and workers of the World's own; the same result for any count).
  SimLoop(Scene scene, Metrics& metrics,
          std::chrono::milliseconds step_command_budget = std::chrono::seconds(5),
          unsigned sim_threads = 1);
  /// Stops the thread.
  ~SimLoop();
  SimLoop(const SimLoop&) = delete;
  SimLoop& operator=(const SimLoop&) = delete;

  /// Starts the simulation thread.
  void start();
  /// Stops and joins it; queued and later commands complete with 503. Idempotent.
  void stop();
  /// Queues a command; its completion runs on the simulation thread.
  void submit(Command command) { queue_.push(std::move(command)); }
  /// The latest published snapshot (never null).
  std::shared_ptr<const Snapshot> latest() const { return latest_.load(); }
  /// Test seam: called on the simulation thread before every World::step; it may throw
  /// (std::bad_alloc, to check the loop survives it). Set before start().
  void set_before_step(std::function<void()> hook) { before_step_ = std::move(hook); }

 private:
  enum class Change { step, command, restart };

  /// A POST /api/step in progress: taken kStepBudget of wall time at a time, so that
  /// commands queued behind it run between chunks.
  struct RunningStep {
    Command command;
    std::uint32_t requested = 0;
    std::uint32_t done = 0;
    Clock::time_point deadline;
  };

  void run();
  void advance();
  void step_once();
  void execute(Command& command);
  CommandResult run_command(CommandKind& kind);
  CommandResult reset(ResetCommand& c);
  void start_step(Command& command);
  void continue_step();
  void finish_step(const char* stopped);
  void world_step();
  void on_step_failure(const std::exception& e);
  CommandResult impulse(const ImpulseCommand& c);
  void anchor(Clock::time_point now);
  double sim_clock(Clock::time_point now) const;
  void publish(Change change);
  void new_scene_info();

  Metrics& metrics_;
  std::unique_ptr<World> world_;
  std::shared_ptr<const SceneInfo> scene_info_;
  std::uint64_t generation_ = 0;
  bool paused_ = false;
  // The running real-time clock: sim_clock(w) = anchor_sim_ + (w − anchor_wall_).
  Clock::time_point anchor_wall_{};
  double anchor_sim_ = 0.0;
  std::deque<std::pair<Clock::time_point, double>> rtf_samples_;  // (wall, sim time)
  double real_time_factor_ = 1.0;
  const std::chrono::milliseconds step_command_budget_;
  std::optional<RunningStep> running_step_;
  std::function<void()> before_step_;
  CommandQueue queue_;
  SnapshotSlot latest_;
  std::thread thread_;
};

}  // namespace tumble::server
