#pragma once
/// Commands from I/O threads to the simulation thread, and the queue that carries them.
/// I/O threads never touch the World: they push a Command, and the simulation thread runs it
/// before its next step and hands the outcome to the command's completion.
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <variant>

#include <nlohmann/json.hpp>

#include "recording.hpp"
#include "timeline.hpp"
#include "tumble/scene.hpp"
#include "tumble/world.hpp"

namespace tumble::server {

/// Why a command was refused or failed; rest_api maps each to an HTTP status.
enum class Failure {
  invalid,      ///< The request asks for something the world cannot do (400).
  not_found,    ///< It names a body that does not exist (404).
  conflict,     ///< It does not fit the world's state, e.g. a step while running (409).
  unavailable,  ///< Shutting down or out of memory: try again later (503).
  internal,     ///< A bug (500).
};

/// A refused or failed command: what was wrong and which request field it was ("" for none).
struct CommandError {
  Failure failure = Failure::invalid;
  std::string message;
  std::string field;
};

/// Pause or resume done: whether the world is paused now.
struct PausedState {
  bool paused = false;
};
/// Reset done: the name of the scene now running.
struct SceneReset {
  std::string scene;
};
/// Integrator switched.
struct IntegratorSet {
  Integrator integrator = Integrator::midpoint;
};
/// Impulse applied.
struct ImpulseApplied {};
/// A POST /api/step answered: steps taken, and why it stopped early (null: it did not).
struct StepReport {
  double time = 0.0;            ///< Sim time after the steps, s.
  std::uint64_t step = 0;       ///< Step count after them.
  std::uint32_t requested = 0;  ///< Steps asked for.
  std::uint32_t done = 0;       ///< Steps taken.
  const char* stopped = nullptr;  ///< "budget", "cancelled", "shutdown", "out of memory".
};

/// A seek done: the world shows this step, paused.
struct SeekDone {
  double time = 0.0;       ///< Its sim time, s.
  std::uint64_t step = 0;  ///< The step.
};
/// Play or speed done: how the loop runs now.
struct PlayState {
  double time = 0.0;       ///< Sim time now, s.
  std::uint64_t step = 0;  ///< Step now.
  bool playing = false;    ///< Replaying the recorded future (not live).
  bool paused = false;     ///< Paused.
  double speed = 1.0;      ///< Sim seconds per wall second aimed at.
};
/// GET …/history: the timeline and where the world is in it.
struct HistoryReport {
  TimelineSummary timeline;      ///< Range, lists, bytes.
  TimelinePoint at;              ///< The step the world shows.
  bool live = true;              ///< At the newest recorded step.
  bool playing = false;          ///< Replaying the recorded future.
  bool paused = false;           ///< Paused.
  double speed = 1.0;            ///< Sim seconds per wall second aimed at.
  std::size_t bytes_limit = 0;   ///< --history-mb in bytes.
  double history_s = 0.0;        ///< --history-s.
};
/// GET …/recording: the run from step 0 to the step shown.
struct RecordingReport {
  std::shared_ptr<const Recording> recording;  ///< Never null.
};

/// A body added (POST …/bodies, answered 201): its id and name.
struct BodyAdded {
  BodyId body = 0;   ///< Its index.
  std::string name;  ///< Its name (given, or "box-<n>").
};

/// What a command did, as data: the simulation thread knows nothing of HTTP.
using CommandOutcome =
    std::variant<CommandError, PausedState, SceneReset, IntegratorSet, ImpulseApplied, StepReport,
                 SeekDone, PlayState, HistoryReport, RecordingReport, BodyAdded>;

/// Builds a CommandError outcome.
CommandOutcome command_error(Failure failure, std::string message, std::string field);

/// Restart from `scene`, or from the running scene when empty.
struct ResetCommand {
  std::optional<Scene> scene;
};
/// Pause (idempotent).
struct PauseCommand {};
/// Resume (idempotent).
struct ResumeCommand {};
/// Take `steps` steps now; only while paused (else 409).
struct StepCommand {
  std::uint32_t steps = 1;
};
/// Apply `impulse` (N·s, world) at `point` (m, world; default the centre of mass).
struct ImpulseCommand {
  std::variant<BodyId, std::string> body;  ///< Index or name (404 when there is none).
  Vec3 impulse = Vec3::Zero();
  std::optional<Vec3> point;
};
/// Switch the flight integrator.
struct SetIntegratorCommand {
  Integrator integrator = Integrator::midpoint;
};

/// Show the world at a recorded step (by step, or the step nearest a sim time in s), paused.
struct SeekCommand {
  std::optional<std::uint64_t> step;  ///< Exactly one of step and time is set.
  std::optional<double> time;
};
/// From a past step: replay the recorded future at `speed`× real time, then go on live at 1×;
/// at the newest step: resume live at `speed`×.
struct PlayCommand {
  double speed = 1.0;
};
/// The real-time factor to aim at (slow motion below 1).
struct SpeedCommand {
  double speed = 1.0;
};
/// Report the timeline (a read: changes nothing).
struct HistoryCommand {};
/// Build the recording of the run up to the step shown (a read: changes nothing).
struct RecordingCommand {};

/// Add a body to the running world (logged: seek, playback and recordings apply it again).
struct AddBodyCommand {
  BodyDef definition;          ///< Parsed and checked like a scene body.
  bool named = false;          ///< False: the body is named "box-<n>" (the first n free).
  std::size_t max_bodies = 0;  ///< --max-bodies: a world already this big refuses (409).
};

/// What a command asks for.
using CommandKind =
    std::variant<ResetCommand, PauseCommand, ResumeCommand, StepCommand, ImpulseCommand,
                 SetIntegratorCommand, SeekCommand, PlayCommand, SpeedCommand, HistoryCommand,
                 RecordingCommand, AddBodyCommand>;

/// Called once with the outcome, on the simulation thread: must be cheap and must not throw
/// (post the work to the caller's executor).
using Completion = std::function<void(CommandOutcome)>;

/// A command and where its outcome goes.
struct Command {
  CommandKind kind;
  Completion done;
};

/// A multi-producer, single-consumer queue; a push wakes the world's loop in the SimPool.
/// Thread-safe.
class CommandQueue {
 public:
  /// Adds a command and calls the wake hook; when the queue is closed the command completes
  /// at once as unavailable.
  void push(Command command);
  /// Called after every push (outside the lock): tells the pool this world has work. Set it
  /// before the first push.
  void set_wake(std::function<void()> wake) { wake_ = std::move(wake); }
  /// Takes every queued command (non-blocking).
  std::deque<Command> drain();
  /// Closes the queue for good; later pushes complete as unavailable.
  void close();
  /// True after close().
  bool closed() const;

 private:
  std::function<void()> wake_;
  mutable std::mutex mutex_;
  std::deque<Command> queue_;
  bool closed_ = false;
};

}  // namespace tumble::server
