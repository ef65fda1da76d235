#include "worlds.hpp"

#include <algorithm>
#include <cstdio>
#include <random>

namespace tumble::server {

namespace net = boost::asio;

bool valid_world_id(std::string_view id) {
  return !id.empty() && id.size() <= 64 && std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-';
  });
}

std::string new_world_token() {
  std::random_device random;  // getrandom(2) on Linux: unpredictable, not a seeded sequence.
  static constexpr char kHex[] = "0123456789abcdef";
  std::string token;
  for (int i = 0; i < 4; ++i) {
    const std::uint32_t word = random();
    for (int nibble = 7; nibble >= 0; --nibble) token += kHex[(word >> (4 * nibble)) & 0xf];
  }
  return token;
}

// ---- HostedWorld -----------------------------------------------------------------------

HostedWorld::HostedWorld(std::string id, std::string token, std::string scene_key, Scene scene,
                         net::io_context& ioc, Metrics& metrics, const ServerOptions& options)
    : id_(std::move(id)),
      token_(std::move(token)),
      scene_key_(std::move(scene_key)),
      sim_(std::move(scene), metrics, std::chrono::milliseconds(options.step_budget_ms),
           static_cast<unsigned>(options.step_threads),
           TimelineLimits{options.history_s,
                          static_cast<std::size_t>(options.history_mb) << 20}),
      broadcaster_(ioc, sim_, metrics, std::chrono::milliseconds(options.render_ms),
                   static_cast<std::size_t>(options.max_viewers)),
      last_used_(Clock::now().time_since_epoch().count()) {}

void HostedWorld::start(SimPool& pool) {
  broadcaster_.set_owner(weak_from_this());
  sim_.attach(pool);
  broadcaster_.start();
}

void HostedWorld::shutdown() {
  broadcaster_.stop();
  broadcaster_.close_all();
  sim_.stop();
}

void HostedWorld::touch() {
  last_used_.store(Clock::now().time_since_epoch().count(), std::memory_order_relaxed);
  if (idle_paused_.exchange(false)) sim_.submit({ResumeCommand{}, nullptr});
}

void HostedWorld::begin_request() {
  requests_.fetch_add(1, std::memory_order_relaxed);
  touch();
}

void HostedWorld::end_request() {
  last_used_.store(Clock::now().time_since_epoch().count(), std::memory_order_relaxed);
  requests_.fetch_sub(1, std::memory_order_relaxed);
}

Clock::duration HostedWorld::idle_for() const {
  const Clock::duration used(last_used_.load(std::memory_order_relaxed));
  return Clock::now() - Clock::time_point(used);
}

bool HostedWorld::idle_pause() {
  // A world its user paused stays as it is: a later request must not resume it.
  if (sim_.latest()->paused || idle_paused_.exchange(true)) return false;
  sim_.submit({PauseCommand{}, nullptr});
  return true;
}

// ---- WorldRegistry ---------------------------------------------------------------------

WorldRegistry::WorldRegistry(net::io_context& ioc, SimPool& pool, Metrics& metrics,
                             const ServerOptions& options, Scene default_scene)
    : ioc_(ioc),
      pool_(pool),
      metrics_(metrics),
      options_(options),
      max_worlds_(static_cast<std::size_t>(options.max_worlds)),
      default_(std::make_shared<HostedWorld>(std::string(kDefaultWorld), "", options.scene,
                                             std::move(default_scene), ioc, metrics, options)),
      sweep_timer_(ioc) {
  worlds_.emplace(default_->id(), default_);
}

WorldRegistry::~WorldRegistry() { stop(); }

void WorldRegistry::start() {
  default_->start(pool_);
  schedule_sweep();
}

void WorldRegistry::stop() {
  std::map<std::string, std::shared_ptr<HostedWorld>, std::less<>> worlds;
  {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    stopped_ = true;
    sweep_timer_.cancel();
    worlds = worlds_;  // The map stays: sessions still look worlds up while they close.
  }
  for (auto& [id, world] : worlds) world->shutdown();
}

std::shared_ptr<HostedWorld> WorldRegistry::find(std::string_view id) const {
  std::lock_guard lock(mutex_);
  const auto it = worlds_.find(id);
  return it == worlds_.end() ? nullptr : it->second;
}

CreateResult WorldRegistry::create(const std::string& id, const std::string& scene_key,
                                   Scene scene) {
  if (!valid_world_id(id)) return {nullptr, false, CreateRefusal::bad_id};
  {
    std::lock_guard lock(mutex_);
    if (const auto it = worlds_.find(id); it != worlds_.end()) {
      if (it->second->scene_key() == scene_key) return {it->second, false};
      return {nullptr, false, CreateRefusal::conflict};
    }
    if (stopped_ || worlds_.size() >= max_worlds_) return {nullptr, false, CreateRefusal::too_many};
  }
  // Built and started outside the lock (a 1,000-body scene takes milliseconds) and before any
  // other thread can find it, then placed under the lock; a create of the same id that won the
  // race meanwhile decides the answer, and this one is shut down again.
  auto world = std::make_shared<HostedWorld>(id, new_world_token(), scene_key, std::move(scene),
                                             ioc_, metrics_, options_);
  world->start(pool_);
  CreateResult result{world, true};
  {
    std::lock_guard lock(mutex_);
    if (const auto it = worlds_.find(id); it != worlds_.end())
      result = it->second->scene_key() == scene_key
                   ? CreateResult{it->second, false}
                   : CreateResult{nullptr, false, CreateRefusal::conflict};
    else if (stopped_ || worlds_.size() >= max_worlds_)
      result = {nullptr, false, CreateRefusal::too_many};
    else
      worlds_.emplace(id, world);
  }
  if (result.world != world) world->shutdown();
  return result;
}

bool WorldRegistry::remove(std::string_view id) {
  std::shared_ptr<HostedWorld> world;
  {
    std::lock_guard lock(mutex_);
    const auto it = worlds_.find(id);
    if (it == worlds_.end() || it->second == default_) return false;
    world = std::move(it->second);
    worlds_.erase(it);
  }
  world->shutdown();
  return true;
}

std::vector<std::shared_ptr<HostedWorld>> WorldRegistry::list() const {
  std::vector<std::shared_ptr<HostedWorld>> out;
  std::lock_guard lock(mutex_);
  out.reserve(worlds_.size());
  out.push_back(default_);
  for (const auto& [id, world] : worlds_)
    if (world != default_) out.push_back(world);
  return out;
}

std::size_t WorldRegistry::viewers() const {
  std::size_t n = 0;
  for (const auto& world : list()) n += world->broadcaster().viewers();
  return n;
}

void WorldRegistry::sweep_idle() {
  const auto pause_after = std::chrono::duration<double>(options_.idle_s);
  const auto remove_after = std::chrono::duration<double>(options_.idle_remove_s);
  for (const auto& world : list()) {
    if (world == default_) continue;
    if (world->broadcaster().viewers() > 0 || world->busy()) {
      world->touch();
      continue;
    }
    const Clock::duration idle = world->idle_for();
    if (idle >= remove_after) {
      if (remove(world->id()))
        std::fprintf(stderr, "tumble-server: world '%s' removed after %.0f s idle\n",
                     world->id().c_str(), std::chrono::duration<double>(idle).count());
    } else if (idle >= pause_after) {
      world->idle_pause();
    }
  }
}

// Every quarter of --idle-s, at most once a second: an idle world is paused within 25 % of
// its limit, and the sweep costs nothing measurable (a lock and a walk of ≤ --max-worlds).
void WorldRegistry::schedule_sweep() {
  std::lock_guard lock(mutex_);
  if (stopped_) return;
  const double period = std::clamp(options_.idle_s / 4.0, 0.05, 1.0);
  sweep_timer_.expires_after(
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period)));
  sweep_timer_.async_wait([this](boost::system::error_code ec) {
    if (ec) return;
    sweep_idle();
    schedule_sweep();
  });
}

}  // namespace tumble::server
