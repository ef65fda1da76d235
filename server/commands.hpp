#pragma once
/// Commands from I/O threads to the simulation thread, and the queue that carries them.
/// I/O threads never touch the World: they push a Command, and the simulation thread runs it
/// before its next step and hands the outcome to the command's completion.
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <variant>

#include <nlohmann/json.hpp>

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

/// What a command did, as data: the simulation thread knows nothing of HTTP.
using CommandOutcome =
    std::variant<CommandError, PausedState, SceneReset, IntegratorSet, ImpulseApplied, StepReport>;

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

/// What a command asks for.
using CommandKind = std::variant<ResetCommand, PauseCommand, ResumeCommand, StepCommand,
                                 ImpulseCommand, SetIntegratorCommand>;

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
