#pragma once
/// The broadcaster: every --render-ms it quantises the latest Snapshot once into a FrameState
/// (docs/protocol.md, version 2), publishes it in the shared FrameStore with a status every
/// 1 s (or at once when paused, integrator or scene changed), and tells every WebSocket
/// session that a newer frame exists. Sessions pull from the store at their own pace. No
/// viewer, no work. Thread-safe.
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>

#include "frame_store.hpp"
#include "metrics.hpp"
#include "sim_loop.hpp"

namespace tumble::server {

class WsSession;

/// The WebSocket "contacts" text message of `set` (docs/protocol.md, "WebSocket"): positions and
/// normals rounded to 1e-4, impulses to 1e-6 N·s.
std::shared_ptr<const std::string> contacts_message(const ContactSet& set);

/// Frame timer plus the set of viewers (weak references, as in Beast's chat-multi example).
class Broadcaster {
 public:
  /// Frames between two periodic status messages (1 s at the default 20 ms).
  static constexpr std::uint32_t kStatusEvery = 50;

  /// Frames every `interval`; at most `max_viewers` sessions may join.
  Broadcaster(boost::asio::io_context& ioc, SimLoop& sim, Metrics& metrics,
              std::chrono::milliseconds interval, std::size_t max_viewers);

  /// Keeps `owner` (what holds this broadcaster) alive while a handler of this broadcaster is
  /// pending, so that a removed world is freed only after its last timer handler ran. Set
  /// before start().
  void set_owner(std::weak_ptr<const void> owner) { owner_ = std::move(owner); }
  /// Starts the frame timer (absolute deadlines: start + k · interval). It runs only while a
  /// viewer is connected.
  void start();
  /// Stops the timer; no frame is made afterwards.
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
  /// The frames made so far, shared by the sessions.
  FrameStore& store() { return store_; }
  /// A viewer turns contact points on (+1) or off (−1) (SimLoop::subscribe_contacts).
  void subscribe_contacts(int delta) { sim_.subscribe_contacts(delta); }
  /// The frame interval.
  std::chrono::milliseconds interval() const { return interval_; }

 private:
  void wake();
  void do_tick();
  void on_tick(boost::system::error_code ec);
  void publish(Clock::time_point now);
  std::shared_ptr<const nlohmann::json> status_if_due(const Snapshot& snap,
                                                      const FrameState& state);
  std::vector<std::shared_ptr<WsSession>> sessions();

  SimLoop& sim_;
  Metrics& metrics_;
  std::weak_ptr<const void> owner_;
  const std::chrono::milliseconds interval_;
  const std::size_t max_viewers_;
  boost::asio::strand<boost::asio::io_context::executor_type> strand_;
  boost::asio::steady_timer timer_;
  Clock::time_point next_{};
  FrameStore store_;
  std::shared_ptr<const FrameState> previous_;  // On strand_: the last frame made.
  std::uint32_t frame_number_ = 0;              // On strand_.
  std::uint32_t status_frame_ = 0;              // On strand_: frame of the last status.
  std::string status_key_;                      // On strand_: what forces a status now.
  std::shared_ptr<const ContactSet> contact_set_;     // On strand_: the last contacts encoded…
  std::shared_ptr<const std::string> contact_text_;  // …and their message.
  bool started_ = false;  // On strand_.
  bool stopped_ = false;  // On strand_.
  bool ticking_ = false;  // On strand_: a timer wait is pending.
  mutable std::mutex mutex_;
  std::unordered_map<const WsSession*, std::weak_ptr<WsSession>> sessions_;
};

}  // namespace tumble::server
