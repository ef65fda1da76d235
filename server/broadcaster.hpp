#pragma once
/// The broadcaster: every --render-ms it encodes the latest Snapshot once and hands the same
/// buffer to every WebSocket session. No viewer, no encoding. Thread-safe.
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>

#include "sim_loop.hpp"

namespace tumble::server {

class WsSession;

/// Frame timer plus the set of viewers (weak references, as in Beast's chat-multi example).
class Broadcaster {
 public:
  /// Frames every `interval`; at most `max_viewers` sessions may join.
  Broadcaster(boost::asio::io_context& ioc, SimLoop& sim, std::chrono::milliseconds interval,
              std::size_t max_viewers);

  /// Starts the frame timer (absolute deadlines: start + k · interval). It runs only while a
  /// viewer is connected.
  void start();
  /// Stops the timer; no frame is sent afterwards.
  void stop();
  /// Adds a session; false when max_viewers are already connected.
  bool join(const std::shared_ptr<WsSession>& session);
  /// Removes a session (idempotent).
  void leave(const WsSession* session);
  /// Sessions connected now.
  std::size_t viewers() const;
  /// Asks every session to close with a close frame (shutdown).
  void close_all();
  /// The scene info of the latest snapshot (what a new viewer is sent first).
  std::shared_ptr<const SceneInfo> current_scene() const { return sim_.latest()->scene; }

 private:
  void wake();
  void do_tick();
  void on_tick(boost::system::error_code ec);
  std::vector<std::shared_ptr<WsSession>> sessions();

  SimLoop& sim_;
  const std::chrono::milliseconds interval_;
  const std::size_t max_viewers_;
  boost::asio::strand<boost::asio::io_context::executor_type> strand_;
  boost::asio::steady_timer timer_;
  Clock::time_point next_{};
  std::uint32_t frame_number_ = 0;
  bool started_ = false;  // On strand_.
  bool stopped_ = false;  // On strand_.
  bool ticking_ = false;  // On strand_: a timer wait is pending.
  mutable std::mutex mutex_;
  std::unordered_map<const WsSession*, std::weak_ptr<WsSession>> sessions_;
};

}  // namespace tumble::server
