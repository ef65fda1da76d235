#pragma once
/// A world's timeline (docs/protocol.md, "Timeline"): checkpoints (copies of the World) every
/// `interval` steps and the log of commands applied, for the last --history-s seconds of sim
/// time within --history-mb bytes; impact markers. Restores any step in its range exactly: the
/// checkpoint at or before it, then the logged commands and steps up to it (the engine is
/// deterministic, so the result is bit-identical to the straight run). Owned and used by the
/// simulation thread alone (SimLoop); not synchronised.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "recording.hpp"
#include "tumble/world.hpp"

namespace tumble::server {

/// How much a timeline keeps.
struct TimelineLimits {
  double history_s = 60.0;                  ///< Sim seconds kept (0: no timeline).
  std::size_t bytes_limit = 64u << 20;      ///< Most bytes of checkpoints, log and markers.
};

/// A step and its sim time.
struct TimelinePoint {
  std::uint64_t step = 0;  ///< World::step_count().
  double time = 0.0;       ///< World::time(), s.
};

/// Steps at which a step began a burst of impacts (the step before had none).
struct ImpactMarker {
  std::uint64_t step = 0;      ///< The step.
  double time = 0.0;           ///< Its sim time, s.
  std::uint32_t impacts = 0;   ///< Impacts that step resolved.
};

/// What GET …/history reports of the timeline (lists newest last, bounded).
struct TimelineSummary {
  bool enabled = false;                 ///< False: --history-s 0, or one checkpoint is too big.
  TimelinePoint from;                   ///< Oldest step that can be shown.
  TimelinePoint to;                     ///< Newest recorded step.
  std::size_t checkpoints = 0;          ///< World copies held.
  std::uint64_t interval = 0;           ///< Steps between checkpoints now.
  std::size_t bytes = 0;                ///< Estimated bytes held (checkpoints, log, markers).
  std::vector<LoggedCommand> commands;  ///< Logged at steps in [from, to], newest kMaxListed.
  bool commands_truncated = false;      ///< More were in range.
  std::vector<ImpactMarker> impacts;    ///< Markers in [from, to], newest kMaxListed.
};

/// The timeline of one world. Not thread-safe: the simulation thread alone uses it.
class Timeline {
 public:
  /// Most entries of each list in a summary.
  static constexpr std::size_t kMaxListed = 1000;
  /// Most impact markers kept.
  static constexpr std::size_t kMaxImpacts = 4096;
  /// Sim time between checkpoints before any thinning, s.
  static constexpr double kBaseInterval = 0.5;

  /// A timeline with these limits; empty until restart().
  explicit Timeline(TimelineLimits limits);

  /// Starts a new run at `world` (just built from `scene_name`, at step 0 or wherever it is):
  /// everything held is dropped, a checkpoint is taken and a reset entry logged.
  void restart(const World& world, const std::string& scene_name);
  /// True when the timeline records (and seek can work).
  bool enabled() const { return enabled_; }
  /// The newest recorded step.
  TimelinePoint head() const { return head_; }
  /// The oldest step that can be restored.
  TimelinePoint from() const;

  /// After a step taken live (world at head_ + 1): moves the head, marks impacts, takes a
  /// checkpoint when one is due, and trims to the limits.
  void record_step(const World& world);
  /// Logs `command`, applied to `world` at its step (== head).
  void record_command(const World& world, LoggedCommand command);
  /// Forgets everything after world.step_count() (the world is at a past step and is about
  /// to change): log entries, checkpoints and markers of later steps; the head moves there.
  void discard_future(const World& world);
  /// Applies the commands logged at world.step_count() (replay of the recorded future).
  void apply_logged_at(World& world) const;
  /// The world at `step` (its logged commands applied), or nullopt when out of range.
  std::optional<World> restore(std::uint64_t step) const;
  /// The step whose time is nearest `time` (s), or nullopt outside [from, head] by more than
  /// half a step.
  std::optional<std::uint64_t> step_at(double time, double dt) const;

  /// The summary for GET …/history.
  TimelineSummary summary() const;
  /// The recording of the run up to `world` (commands logged at steps ≤ its step), or nullopt
  /// when the log no longer reaches back to step 0 or is too long.
  std::optional<Recording> recording(const World& world) const;

  /// Estimated bytes held now.
  std::size_t bytes() const { return checkpoint_bytes_ + log_bytes() + marker_bytes(); }
  /// The byte bound.
  std::size_t bytes_limit() const { return limits_.bytes_limit; }
  /// Sim seconds kept.
  double history_s() const { return limits_.history_s; }

 private:
  struct Checkpoint {
    TimelinePoint at;
    World world;
    std::size_t bytes = 0;
  };

  std::size_t log_bytes() const;
  std::size_t marker_bytes() const;
  void take_checkpoint(const World& world);
  void trim();
  void thin();
  void drop_oldest_checkpoint();

  TimelineLimits limits_;
  bool enabled_ = false;
  Scene scene_;                           // The run's scene at step 0.
  bool origin_kept_ = true;               // log_ still reaches back to step 0.
  std::uint64_t base_interval_ = 1;       // Steps, from kBaseInterval.
  std::uint64_t interval_ = 1;            // Steps; doubled by thinning.
  TimelinePoint head_;
  std::deque<Checkpoint> checkpoints_;    // Ascending steps.
  std::size_t checkpoint_bytes_ = 0;
  std::deque<LoggedCommand> log_;         // Ascending steps, in the order applied.
  std::deque<ImpactMarker> impacts_;      // Ascending steps.
  bool impacts_last_step_ = false;        // The head step resolved impacts.
};

/// Estimated bytes of a copy of `world` (bodies, their definitions, contact cache).
std::size_t estimate_world_bytes(const World& world);

}  // namespace tumble::server
