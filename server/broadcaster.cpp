#include "broadcaster.hpp"

#include <cmath>

#include <boost/asio/post.hpp>

#include "frame.hpp"
#include "ws_session.hpp"

namespace tumble::server {

namespace net = boost::asio;

std::shared_ptr<const std::string> contacts_message(const ContactSet& set) {
  const auto round = [](double v, double unit) { return std::round(v / unit) * unit; };
  nlohmann::json points = nlohmann::json::array();
  for (const ContactView& c : set.points) {
    points.push_back({round(c.position.x(), 1e-4), round(c.position.y(), 1e-4),
                      round(c.position.z(), 1e-4), round(c.normal.x(), 1e-4),
                      round(c.normal.y(), 1e-4), round(c.normal.z(), 1e-4),
                      round(c.impulse, 1e-6), c.solved ? 1 : 0});
  }
  const nlohmann::json message{{"type", "contacts"},
                               {"step", set.step},
                               {"points", std::move(points)},
                               {"truncated", set.truncated}};
  return std::make_shared<const std::string>(
      message.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

Broadcaster::Broadcaster(net::io_context& ioc, SimLoop& sim, Metrics& metrics,
                         std::chrono::milliseconds interval, std::size_t max_viewers)
    : sim_(sim),
      metrics_(metrics),
      interval_(interval),
      max_viewers_(max_viewers),
      strand_(net::make_strand(ioc)),
      timer_(strand_) {}

void Broadcaster::start() {
  net::post(strand_, [this, owner = owner_.lock()] {
    started_ = true;
    wake();
  });
}

void Broadcaster::wake() {
  if (!started_ || stopped_ || ticking_ || viewers() == 0) return;
  ticking_ = true;
  next_ = Clock::now() + interval_;
  do_tick();
}

void Broadcaster::stop() {
  net::post(strand_, [this, owner = owner_.lock()] {
    stopped_ = true;
    timer_.cancel();
  });
}

bool Broadcaster::join(const std::shared_ptr<WsSession>& session) {
  std::lock_guard lock(mutex_);
  std::erase_if(sessions_, [](const auto& kv) { return kv.second.expired(); });
  if (sessions_.size() >= max_viewers_) return false;
  sessions_.emplace(session.get(), session);
  // The timer sleeps while nobody watches.
  net::post(strand_, [this, owner = owner_.lock()] { wake(); });
  return true;
}

void Broadcaster::leave(const WsSession* session) {
  std::lock_guard lock(mutex_);
  sessions_.erase(session);
}

std::size_t Broadcaster::viewers() const {
  std::lock_guard lock(mutex_);
  std::size_t n = 0;
  for (const auto& kv : sessions_) n += kv.second.expired() ? 0 : 1;
  return n;
}

std::vector<std::shared_ptr<WsSession>> Broadcaster::sessions() {
  std::vector<std::shared_ptr<WsSession>> live;
  std::lock_guard lock(mutex_);
  live.reserve(sessions_.size());
  for (const auto& kv : sessions_)
    if (auto s = kv.second.lock()) live.push_back(std::move(s));
  return live;
}

void Broadcaster::close_all() {
  for (const auto& s : sessions()) s->close();
}

void Broadcaster::do_tick() {
  timer_.expires_at(next_);
  timer_.async_wait(
      [this, owner = owner_.lock()](boost::system::error_code ec) { on_tick(ec); });
}

// Quantise once, publish, then only tell each session (a post per viewer): each takes the
// newest frame relative to what it last sent when its previous write is done, so encodings
// are shared between viewers in step and a slow one never queues (FrameStore, WsSession).
void Broadcaster::on_tick(boost::system::error_code ec) {
  if (ec || stopped_) {
    ticking_ = false;
    return;
  }
  const Clock::time_point now = Clock::now();
  const auto live = sessions();
  if (live.empty()) {  // No viewer: no frame and no timer until one joins.
    ticking_ = false;
    return;
  }
  publish(now);
  for (const auto& s : live) s->notify();
  next_ += interval_;
  std::uint64_t skipped = 0;
  for (; next_ <= now; ++skipped) next_ += interval_;  // Late by over a period: skip, don't burst.
  if (skipped > 0) metrics_.count_ticks_skipped(skipped);
  do_tick();
}

void Broadcaster::publish(Clock::time_point now) {
  const double cpu0 = thread_cpu_seconds();
  const std::shared_ptr<const Snapshot> snap = sim_.latest();
  auto state = make_frame_state(*snap, frame_number_++, frame_time(*snap, now), previous_.get());
  auto status = status_if_due(*snap, *state);
  // Contacts are encoded once per snapshot that carries them, shared by the viewers that asked.
  if (snap->contacts != contact_set_) {
    contact_set_ = snap->contacts;
    contact_text_ = contact_set_ ? contacts_message(*contact_set_) : nullptr;
  }
  store_.publish(state, snap->scene, std::move(status), contact_text_,
                 contact_set_ ? contact_set_->step : 0);
  previous_ = std::move(state);
  metrics_.add_stream_cpu(thread_cpu_seconds() - cpu0);
}

std::shared_ptr<const nlohmann::json> Broadcaster::status_if_due(const Snapshot& snap,
                                                                 const FrameState& state) {
  const std::string key = std::to_string(snap.scene->generation) + (snap.paused ? "p" : "r") +
                          (snap.live ? "l" : snap.playing ? "y" : "h") +
                          std::to_string(snap.speed) + std::string(to_string(snap.integrator));
  if (key == status_key_ && state.number - status_frame_ < kStatusEvery) return nullptr;
  status_key_ = key;
  status_frame_ = state.number;
  const std::size_t n = snap.bodies->size();
  return std::make_shared<const nlohmann::json>(nlohmann::json{
      {"type", "status"},
      {"frame", state.number},
      {"time", snap.time},
      {"step", snap.step},
      {"paused", snap.paused},
      {"live", snap.live},
      {"playing", snap.playing},
      {"speed", snap.speed},
      {"real_time_factor", snap.real_time_factor},
      {"integrator", std::string(to_string(snap.integrator))},
      {"bodies", n},
      {"awake", snap.awake},
      {"asleep", n - snap.awake - snap.frozen},
      {"frozen", snap.frozen}});
}

}  // namespace tumble::server
