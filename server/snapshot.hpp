#pragma once
/// Immutable views of the simulation, published by the simulation thread after every step and
/// read by I/O threads (REST, broadcaster). A published snapshot never changes: thread-safe.
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tumble/body.hpp"
#include "tumble/scene.hpp"
#include "tumble/world.hpp"

namespace tumble::server {

using Clock = std::chrono::steady_clock;

/// A scene as the server shows it; one per reset (a generation), shared by its snapshots.
struct SceneInfo {
  std::uint64_t generation = 0;                  ///< 1 for the first scene, +1 per reset.
  Scene scene;                                   ///< As loaded (initial integrator).
  std::vector<BodyConstants> constants;          ///< Per body, for vertices and sizes.
  std::shared_ptr<const std::string> message;    ///< The WebSocket "scene" text message.
};

/// Builds the scene info (and its WebSocket message) for a world built from `scene`.
std::shared_ptr<const SceneInfo> make_scene_info(std::uint64_t generation, const Scene& scene,
                                                 std::vector<BodyConstants> constants);

/// One body at one instant (SI, world frame).
struct BodyPose {
  Vec3 position = Vec3::Zero();          ///< Centre of mass, m.
  Mat3 rotation = Mat3::Identity();      ///< Body → world.
  Vec3 velocity = Vec3::Zero();          ///< m/s.
  Vec3 angular_velocity = Vec3::Zero();  ///< rad/s, world frame.
  Activity activity = Activity::awake;   ///< awake / asleep / frozen.
};

/// The contact points of a step, for viewers that asked for them (WebSocket "contacts").
struct ContactSet {
  std::uint64_t step = 0;             ///< The step they are from.
  std::vector<ContactView> points;    ///< At most kMaxPoints, in World::contacts order.
  bool truncated = false;             ///< The step had more than kMaxPoints.
  /// Most points kept per step.
  static constexpr std::size_t kMaxPoints = 4096;
};

/// The simulation after a step (or a command).
struct Snapshot {
  std::shared_ptr<const SceneInfo> scene;               ///< Never null.
  double time = 0.0;                                    ///< Sim time, s.
  std::uint64_t step = 0;                               ///< Steps since the reset.
  bool paused = false;                                  ///< Paused by a command.
  double speed = 1.0;                                   ///< Sim s per wall s aimed at.
  bool live = true;                                     ///< At the timeline's newest step.
  bool playing = false;                                 ///< Replaying the recorded future.
  std::size_t history_bytes = 0;                        ///< Estimated bytes of the timeline.
  double real_time_factor = 0.0;                        ///< Sim s per wall s (0 paused).
  double energy = 0.0;                                  ///< Total energy, J.
  Integrator integrator = Integrator::midpoint;         ///< In use now.
  std::size_t awake = 0;                                ///< Bodies awake.
  std::size_t frozen = 0;                               ///< Bodies frozen (went non-finite).
  std::shared_ptr<const std::vector<BodyPose>> bodies;  ///< Per body, never null.
  /// The previous step's poses (for interpolation) or null (first state of a scene, or the
  /// state changed by a command rather than by a step).
  std::shared_ptr<const std::vector<BodyPose>> previous_bodies;
  double previous_time = 0.0;  ///< Sim time of previous_bodies, s.
  /// Wall instant at which the running real-time clock reaches `time` (steps are taken
  /// ahead of the wall clock, so a frame at wall time w shows sim time time − (wall_time − w)).
  Clock::time_point wall_time{};
  /// The last step's contacts; null unless a viewer subscribed (SimLoop::subscribe_contacts).
  std::shared_ptr<const ContactSet> contacts;
};

/// The sim time a frame taken at wall instant `at` shows: `time` while paused or when no
/// previous step is known, else the real-time clock (at `speed`) clamped to
/// [previous_time, time].
double frame_time(const Snapshot& s, Clock::time_point at);

/// The scene JSON as GET /api/scene returns it (with the integrator in use).
nlohmann::json scene_json(const Snapshot& s);

/// The GET /api/state document (docs/protocol.md).
nlohmann::json state_json(const Snapshot& s);

}  // namespace tumble::server
