#pragma once
/// One world's fixed-step real-time loop: it alone owns the tumble::World. A thread of the
/// SimPool calls service(), which runs the commands of I/O threads, then the steps that are
/// due, and publishes an immutable Snapshot after every step and every command; only one
/// pool thread services a loop at a time.
///
/// Usage:
///   SimPool pool(2);
///   SimLoop sim(tumble::load_scene("seed"), metrics);
///   pool.add(sim);
///   sim.submit({PauseCommand{}, [](CommandOutcome r) { … }});
///   auto snap = sim.latest();   // any thread
///   sim.stop();
#include <deque>
#include <functional>
#include <optional>
#include <memory>
#include <mutex>
#include <atomic>
#include <utility>

#include "commands.hpp"
#include "metrics.hpp"
#include "snapshot.hpp"
#include "timeline.hpp"
#include "tumble/world.hpp"

namespace tumble::server {

class SimPool;

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

  /// Slowest and fastest live speed (POST …/speed), sim seconds per wall second.
  static constexpr double kMinLiveSpeed = 0.1;
  static constexpr double kMaxLiveSpeed = 4.0;
  /// Slowest and fastest playback of the recorded future (POST …/play).
  static constexpr double kMinPlaySpeed = 0.25;
  static constexpr double kMaxPlaySpeed = 4.0;

  /// Builds the world (throws tumble::InvalidInput for an invalid scene) and publishes its
  /// first snapshot. Nothing runs until a SimPool services it. Each step runs on
  /// `step_threads` threads (the pool's thread and workers of the World's own; the same
  /// result for any count). `timeline`: what its history keeps (docs/protocol.md, Timeline).
  SimLoop(Scene scene, Metrics& metrics,
          std::chrono::milliseconds step_command_budget = std::chrono::seconds(5),
          unsigned step_threads = 1, TimelineLimits timeline = {});
  /// Stops.
  ~SimLoop();
  SimLoop(const SimLoop&) = delete;
  SimLoop& operator=(const SimLoop&) = delete;

  /// Hands the loop to `pool`, which services it from now on. Once, before any submit.
  void attach(SimPool& pool);
  /// Takes the loop out of its pool (waits for a running service to end); queued and later
  /// commands complete as unavailable. Idempotent; not from a pool thread.
  void stop();
  /// Runs queued commands, then a chunk of a running POST /api/step or the steps the
  /// real-time clock has reached (at most kStepBudget of wall time). Returns when it next has
  /// work: a past or present instant when still behind, max() when only a command can bring
  /// work (paused). Called by one pool thread at a time.
  Clock::time_point service();
  /// Queues a command (and wakes the loop); its completion runs on a simulation thread.
  void submit(Command command) { queue_.push(std::move(command)); }
  /// The latest published snapshot (never null).
  std::shared_ptr<const Snapshot> latest() const { return latest_.load(); }
  /// Counts a viewer that wants contact points (+1) or no longer does (−1); while the count is
  /// above 0 every published snapshot carries the last step's contacts. Thread-safe.
  void subscribe_contacts(int delta) { contact_subscribers_.fetch_add(delta); }
  /// Viewers that want contact points now. Thread-safe.
  int contact_subscribers() const { return contact_subscribers_.load(); }
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

  void advance();
  void step_once();
  void execute(Command& command);
  CommandOutcome run_command(CommandKind& kind);
  CommandOutcome reset(ResetCommand& c);
  void start_step(Command& command);
  void continue_step();
  void finish_step(const char* stopped);
  void world_step();
  void after_step();
  bool at_past() const;
  void log_command(LoggedCommand command);
  CommandOutcome pause_or_resume(bool pause);
  CommandOutcome seek(const SeekCommand& c);
  CommandOutcome play(const PlayCommand& c);
  CommandOutcome history() const;
  CommandOutcome recording() const;
  PlayState play_state() const;
  void on_step_failure(const std::exception& e);
  CommandOutcome impulse(const ImpulseCommand& c);
  CommandOutcome add_body(AddBodyCommand& c);
  void anchor(Clock::time_point now);
  double sim_clock(Clock::time_point now) const;
  void publish(Change change);
  void new_scene_info();

  Metrics& metrics_;
  std::unique_ptr<World> world_;
  std::shared_ptr<const SceneInfo> scene_info_;
  std::uint64_t generation_ = 0;
  bool paused_ = false;
  bool playing_ = false;  // Replaying the recorded future from a past step.
  double speed_ = 1.0;    // Sim seconds per wall second aimed at.
  Timeline timeline_;
  // The running real-time clock: sim_clock(w) = anchor_sim_ + speed_ · (w − anchor_wall_).
  Clock::time_point anchor_wall_{};
  double anchor_sim_ = 0.0;
  std::deque<std::pair<Clock::time_point, double>> rtf_samples_;  // (wall, sim time)
  double real_time_factor_ = 1.0;
  const std::chrono::milliseconds step_command_budget_;
  std::optional<RunningStep> running_step_;
  std::function<void()> before_step_;
  CommandQueue queue_;
  SnapshotSlot latest_;
  std::atomic<SimPool*> pool_{nullptr};
  std::atomic<bool> stopped_{false};
  std::atomic<int> contact_subscribers_{0};
  std::vector<ContactView> contact_scratch_;  // Simulation thread: World::contacts' buffer.
  std::size_t loaded_bodies_ = 0;  // Bodies of the scene as loaded (a reset drops the added).
};

}  // namespace tumble::server
