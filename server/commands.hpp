#pragma once
/// Commands from I/O threads to the simulation thread, and the queue that carries them.
/// I/O threads never touch the World: they push a Command, and the simulation thread runs it
/// before its next step and hands the outcome to the command's completion.
#include <condition_variable>
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

/// The outcome of a command, as REST answers it: an HTTP status and a JSON body.
struct CommandResult {
  unsigned status = 200;  ///< 200, or the 4xx of docs/protocol.md.
  nlohmann::json body;    ///< {"ok": true, …} or {"error": …, "field": …}.
};

/// Builds a 4xx result {"error": message, "field": field}.
CommandResult command_error(unsigned status, std::string message, std::string field);

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
using Completion = std::function<void(CommandResult)>;

/// A command and where its outcome goes.
struct Command {
  CommandKind kind;
  Completion done;
};

/// A multi-producer, single-consumer queue with a condition variable, so that the
/// simulation thread can sleep until a command arrives or its next step is due.
/// Thread-safe.
class CommandQueue {
 public:
  /// Adds a command; when the queue is closed the command completes at once with 503.
  void push(Command command);
  /// Takes every queued command (non-blocking).
  std::deque<Command> drain();
  /// Blocks until a command is queued or the queue is closed.
  void wait();
  /// Blocks until a command is queued, the queue is closed or `deadline` passes.
  void wait_until(std::chrono::steady_clock::time_point deadline);
  /// Wakes the consumer for good; later pushes complete with 503.
  void close();
  /// True after close().
  bool closed() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Command> queue_;
  bool closed_ = false;
};

}  // namespace tumble::server
