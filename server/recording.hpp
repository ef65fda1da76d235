#pragma once
/// The command log of a world's timeline and exact replay files (docs/protocol.md, "Timeline"):
/// what was applied to a World at which step, how to apply it again, the digest of a World's
/// state, and the JSON of a recording. Its own small target (tumble_recording: engine, scene_io,
/// nlohmann-json) so that tumble-sim replays files without the server. Pure functions and plain
/// data; not synchronised.
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tumble/scene.hpp"
#include "tumble/world.hpp"

namespace tumble::server {

/// Version of the recording document ("format": "tumble-recording", "version": 1).
inline constexpr int kRecordingVersion = 1;

/// What a logged command did.
enum class LoggedKind : std::uint8_t {
  reset,       ///< The run began (the first entry, step 0); no effect on replay.
  impulse,     ///< World::apply_impulse(body, impulse[, point]).
  integrator,  ///< World::set_integrator(integrator).
  pause,       ///< The loop paused; no effect on the World.
  resume,      ///< The loop resumed; no effect on the World.
  add_body,    ///< World::add_body(definition); `body` is the id it got.
};

/// Name of a kind as written in JSON ("impulse" …).
const char* to_string(LoggedKind kind);

/// One command applied to a World when it had taken `step` steps (after that step, before the
/// next). Plain data.
struct LoggedCommand {
  std::uint64_t step = 0;           ///< World::step_count() when it was applied.
  double time = 0.0;                ///< World::time() then, s.
  LoggedKind kind = LoggedKind::reset;
  BodyId body = 0;                  ///< impulse: the body's index.
  Vec3 impulse = Vec3::Zero();      ///< impulse: N·s, world.
  std::optional<Vec3> point;        ///< impulse: m, world (none: the centre of mass).
  Integrator integrator = Integrator::exact;  ///< integrator: the new one.
  std::string scene;                ///< reset: the scene's name.
  std::shared_ptr<const BodyDef> definition;  ///< add_body: the body added (never null then).
};

/// Applies a logged command to `world` exactly as the simulation did (impulse, integrator,
/// add_body; the other kinds change nothing). Throws tumble::InvalidInput for a body out of
/// range, or an add_body the World refuses or whose id differs from the logged one.
void apply_logged(World& world, const LoggedCommand& command);

/// 64-bit FNV-1a over every body's state doubles in body order: x (3), R (9, column-major,
/// as Eigen stores it), P (3), L (3), each as its 8 little-endian IEEE-754 bytes.
std::uint64_t state_digest(const World& world);

/// A digest as 16 lowercase hex digits.
std::string digest_hex(std::uint64_t digest);

/// One log entry as JSON: {"step", "time", "kind", …kind's fields} (docs/protocol.md).
nlohmann::json logged_json(const LoggedCommand& command);

/// An exact replay file: a scene, the commands applied from step 0, and the end state's digest.
struct Recording {
  Scene scene;                          ///< The run's scene at step 0 (its integrator then).
  std::vector<LoggedCommand> commands;  ///< In the order applied; steps non-decreasing.
  std::uint64_t final_step = 0;         ///< Steps taken by the end.
  double final_time = 0.0;              ///< World::time() at the end, s.
  std::uint64_t digest = 0;             ///< state_digest() at the end (after its commands).
};

/// Most commands a recording holds (its JSON stays under about 15 MB).
inline constexpr std::size_t kMaxRecordingCommands = 100000;
/// Most steps a recording may ask tumble-sim to take (a day at 60 Hz).
inline constexpr std::uint64_t kMaxRecordingSteps = 5184000;

/// The recording document (docs/protocol.md, "Recording").
nlohmann::json recording_json(const Recording& recording);

/// A recording file that cannot be used: the offending field ("commands[3].body").
struct RecordingError : std::runtime_error {
  RecordingError(std::string field, const std::string& message)
      : std::runtime_error(message), field(std::move(field)) {}
  std::string field;  ///< "" for the whole document.
};

/// A body definition as a scene's body JSON (scene_io's schema).
nlohmann::json body_json(const BodyDef& body);

/// Parses one body definition with scene_io's rules; throws SceneParseError naming the field
/// relative to the body ("mass", "size[1]"; "" for the whole value).
BodyDef body_from_json(const nlohmann::json& body);

/// Parses and checks a recording document; throws RecordingError naming the field.
Recording parse_recording(const nlohmann::json& document);

/// The end of a replay.
struct ReplayResult {
  std::uint64_t step = 0;    ///< Steps taken.
  double time = 0.0;         ///< Sim time, s.
  std::uint64_t digest = 0;  ///< state_digest() at the end.
};

/// Replays a recording from step 0 on `threads` threads (any count gives the same result):
/// at each step its commands, then a step, until final_step and its commands. Throws
/// RecordingError for a command the World refuses.
ReplayResult replay(const Recording& recording, unsigned threads = 1);

}  // namespace tumble::server
