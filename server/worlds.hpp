#pragma once
/// The worlds one server hosts (docs/protocol.md, "Worlds"): each an independent simulation
/// with its own SimLoop, stepped by the server's shared SimPool, and its own Broadcaster for
/// its viewers. The world `default` is made at start from --scene; every unprefixed route and
/// `/ws` without `?world=` address it, and it is never removed. Others are created by
/// `PUT /api/worlds/{id}` with a write token, and paused, then removed, when idle.
#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "broadcaster.hpp"
#include "commands.hpp"
#include "metrics.hpp"
#include "options.hpp"
#include "sim_loop.hpp"
#include "sim_pool.hpp"

namespace tumble::server {

/// The id of the world the unprefixed routes address.
inline constexpr std::string_view kDefaultWorld = "default";

/// True for a valid world id: [a-z0-9-]{1,64}.
bool valid_world_id(std::string_view id);

/// One hosted world. Its parts are thread-safe; the object lives while the registry or any
/// session holds it (a removed world is shut down at once, freed when its last viewer goes).
class HostedWorld : public std::enable_shared_from_this<HostedWorld> {
 public:
  /// Builds the world's loop and broadcaster (throws tumble::InvalidInput for a bad scene);
  /// `token`: its write token ("" for the default world); `scene_key`: what it was created
  /// from, to tell an idempotent PUT from a conflicting one.
  HostedWorld(std::string id, std::string token, std::string scene_key, Scene scene,
              boost::asio::io_context& ioc, Metrics& metrics, const ServerOptions& options);
  /// Starts stepping on `pool` and broadcasting. Once.
  void start(SimPool& pool);
  /// Stops the loop (queued commands answer as unavailable) and closes its viewers.
  void shutdown();

  /// Its id. Immutable.
  const std::string& id() const { return id_; }
  /// Its write token ("" for the default world: the server's --token guards it). Immutable.
  const std::string& token() const { return token_; }
  /// What it was created from (a bundled scene name, or the scene's JSON). Immutable.
  const std::string& scene_key() const { return scene_key_; }
  /// Its loop (commands, snapshots).
  SimLoop& sim() { return sim_; }
  /// Its broadcaster (viewers).
  Broadcaster& broadcaster() { return broadcaster_; }

  /// A request or a viewer used the world now; a world paused for idleness resumes.
  void touch();
  /// A request addressing the world began (touches it); until its end_request() the world is
  /// not idle, however long the request runs (a POST /api/step may take --step-budget-ms).
  void begin_request();
  /// That request was answered (touches it again).
  void end_request();
  /// Requests begun and not yet answered.
  bool busy() const { return requests_.load(std::memory_order_relaxed) > 0; }
  /// Wall time since it was last used.
  Clock::duration idle_for() const;
  /// Pauses it for idleness (a touch resumes it); false if it was paused already (by idleness
  /// or by its user, whose pause a touch leaves alone).
  bool idle_pause();

 private:
  const std::string id_;
  const std::string token_;
  const std::string scene_key_;
  SimLoop sim_;
  Broadcaster broadcaster_;
  std::atomic<Clock::rep> last_used_;
  std::atomic<bool> idle_paused_{false};
  std::atomic<int> requests_{0};
};

/// Why a create was refused.
enum class CreateRefusal { none, bad_id, conflict, too_many };

/// The outcome of WorldRegistry::create.
struct CreateResult {
  std::shared_ptr<HostedWorld> world;  ///< The world (null when refused).
  bool created = false;                ///< False: it existed with the same scene.
  CreateRefusal refusal = CreateRefusal::none;
};

/// The server's worlds, by id, and the idle sweep. Thread-safe.
class WorldRegistry {
 public:
  /// Makes the default world from `scene` (throws tumble::InvalidInput for a bad scene).
  WorldRegistry(boost::asio::io_context& ioc, SimPool& pool, Metrics& metrics,
                const ServerOptions& options, Scene default_scene);
  /// Shuts every world down.
  ~WorldRegistry();
  WorldRegistry(const WorldRegistry&) = delete;
  WorldRegistry& operator=(const WorldRegistry&) = delete;

  /// Starts the default world and the idle sweep.
  void start();
  /// Stops the idle sweep and shuts every world down (viewers get close frames).
  void stop();

  /// The world `id`, or null.
  std::shared_ptr<HostedWorld> find(std::string_view id) const;
  /// The default world (never null).
  std::shared_ptr<HostedWorld> default_world() const { return default_; }
  /// Creates world `id` from `scene` (built and started here; throws tumble::InvalidInput
  /// for a bad scene), or returns the existing one when `scene_key` matches.
  CreateResult create(const std::string& id, const std::string& scene_key, Scene scene);
  /// Removes and shuts down world `id`; false if there is none (or it is the default).
  bool remove(std::string_view id);
  /// Every world, the default first, then by id.
  std::vector<std::shared_ptr<HostedWorld>> list() const;
  /// Viewers of all worlds.
  std::size_t viewers() const;
  /// Most worlds (--max-worlds, the default counted).
  std::size_t max_worlds() const { return max_worlds_; }
  /// Pauses worlds idle past --idle-s and removes those idle past --idle-remove-s (called by
  /// the sweep timer; public for tests).
  void sweep_idle();

 private:
  void schedule_sweep();

  boost::asio::io_context& ioc_;
  SimPool& pool_;
  Metrics& metrics_;
  const ServerOptions& options_;
  const std::size_t max_worlds_;
  std::shared_ptr<HostedWorld> default_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<HostedWorld>, std::less<>> worlds_;
  boost::asio::steady_timer sweep_timer_;
  bool stopped_ = false;  // Under mutex_.
};

/// A fresh write token: 128 random bits as 32 lowercase hex digits.
std::string new_world_token();

}  // namespace tumble::server
