#include "broadcaster.hpp"

#include <boost/asio/post.hpp>

#include "frame.hpp"
#include "ws_session.hpp"

namespace tumble::server {

namespace net = boost::asio;

Broadcaster::Broadcaster(net::io_context& ioc, SimLoop& sim, std::chrono::milliseconds interval,
                         std::size_t max_viewers)
    : sim_(sim),
      interval_(interval),
      max_viewers_(max_viewers),
      strand_(net::make_strand(ioc)),
      timer_(strand_) {}

void Broadcaster::start() {
  net::post(strand_, [this] {
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
  net::post(strand_, [this] {
    stopped_ = true;
    timer_.cancel();
  });
}

bool Broadcaster::join(const std::shared_ptr<WsSession>& session) {
  std::lock_guard lock(mutex_);
  std::erase_if(sessions_, [](const auto& kv) { return kv.second.expired(); });
  if (sessions_.size() >= max_viewers_) return false;
  sessions_.emplace(session.get(), session);
  net::post(strand_, [this] { wake(); });  // The timer sleeps while nobody watches.
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
  timer_.async_wait([this](boost::system::error_code ec) { on_tick(ec); });
}

// Copy the frame once into a shared buffer; lock the weak references outside the mutex's
// critical work and deliver to each (Beast chat-multi shared_state::send).
void Broadcaster::on_tick(boost::system::error_code ec) {
  if (ec || stopped_) {
    ticking_ = false;
    return;
  }
  const Clock::time_point now = Clock::now();
  const auto live = sessions();
  if (live.empty()) {  // No viewer: no encoding and no timer until one joins.
    ticking_ = false;
    return;
  }
  const std::shared_ptr<const Snapshot> snap = sim_.latest();
  auto frame = std::make_shared<const std::string>(
      encode_frame(*snap, frame_number_++, frame_time(*snap, now)));
  for (const auto& s : live) s->deliver(frame, snap->scene);
  next_ += interval_;
  while (next_ <= now) next_ += interval_;  // Late by more than a period: skip, don't burst.
  do_tick();
}

}  // namespace tumble::server
