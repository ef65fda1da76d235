#pragma once
/// One WebSocket viewer (/ws), protocol version 2. All its work runs on its own strand. It
/// sends the scene text message first (and again after each reset, before that scene's
/// frames), status text messages, and binary frames pulled from the broadcaster's FrameStore:
/// when its previous write is done it takes the newest frame, encoded against the frame it
/// sent last (a keyframe when it has none of this scene). Nothing queues: a viewer that is
/// slower than the frame rate gets fewer frames (each skipped one counts as dropped), never a
/// stale one. A client that acknowledges frames (`{"type":"ack","frame":n,"window":w}`) is
/// also held to w ≤ kAckWindow unacknowledged frames, so that a browser that reads its socket faster than it
/// can process gets no queue either. A client that sends `{"type":"contacts","on":true}` gets,
/// after each frame sent, the "contacts" text message of the newest step when that step differs
/// from the last one sent (`"on":false` stops it). Other client messages are ignored (over 4 KiB: the
/// connection is closed). Every half
/// viewer timeout it sends a ping with a random payload; a viewer that has not echoed it in a
/// pong within the timeout (it does not read, or reads too slowly to reach the ping) is
/// dropped, so its slot under --max-viewers is freed.
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "admission.hpp"
#include "metrics.hpp"
#include "frame_state.hpp"
#include "snapshot.hpp"

namespace tumble::server {

class Broadcaster;

/// A WebSocket connection to a viewer.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  /// Largest message a client may send, bytes.
  static constexpr std::size_t kMaxClientMessage = 4096;
  /// Frames an acknowledging client may have unacknowledged (it may ask for fewer).
  static constexpr std::size_t kAckWindow = 6;
  /// A frame that changes nothing is still sent this often (it carries the sim time), ms.
  static constexpr int kHeartbeatMs = 200;

  /// Takes over an accepted socket (its executor must be a strand); `timeout`: a ping left
  /// unanswered this long drops the viewer; `slot`: its place under --max-connections;
  /// `owner`: what holds `broadcaster` (its world), kept alive while the session lives.
  WsSession(boost::asio::ip::tcp::socket&& socket, Broadcaster& broadcaster, Metrics& metrics,
            std::chrono::milliseconds timeout = std::chrono::seconds(15),
            ConnectionCount::Slot slot = nullptr, std::shared_ptr<const void> owner = nullptr);

  /// Completes the upgrade of `request` and starts sending.
  void run(boost::beast::http::request<boost::beast::http::string_body> request);
  /// Tells the session that the broadcaster published a newer frame. Thread-safe.
  void notify();
  /// Closes with a close frame ("going away"). Thread-safe.
  void close();

 private:
  void on_accept(boost::beast::error_code ec);
  void do_read();
  void on_read(boost::beast::error_code ec, std::size_t bytes);
  void on_notify();
  void on_client_message();
  bool busy() const;
  void do_write();
  bool write_frame(const std::shared_ptr<const FrameState>& state);
  void write_text(std::shared_ptr<const std::string> text);
  void on_write(bool is_frame, boost::beast::error_code ec, std::size_t bytes);
  void do_close();
  void finish();
  void do_ping_timer();
  void on_ping_timer(boost::beast::error_code ec);
  void drop();

  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  std::shared_ptr<const void> owner_;  // Declared before broadcaster_: outlives its use.
  Broadcaster& broadcaster_;
  Metrics& metrics_;
  boost::beast::flat_buffer read_buffer_;
  boost::asio::steady_timer ping_timer_;
  const std::chrono::milliseconds timeout_;
  ConnectionCount::Slot slot_;
  boost::beast::websocket::ping_data ping_payload_;  // Expected back in the pong.
  bool ping_outstanding_ = false;
  int ticks_unanswered_ = 0;
  std::shared_ptr<const std::string> pending_scene_;  // Text message to send first.
  std::shared_ptr<const std::string> in_flight_;      // Kept alive while being written.
  std::shared_ptr<const FrameState> base_;            // The frame sent last (this scene).
  std::uint64_t generation_ = 0;                      // Scene whose message was sent last.
  std::uint64_t status_sent_ = 0;                     // Status sequence sent last.
  std::uint64_t dropped_ = 0;                         // Frames this viewer never got.
  std::chrono::steady_clock::time_point last_frame_at_{};
  std::deque<std::uint32_t> unacked_;                 // Frames sent, not acknowledged.
  bool acking_ = false;                               // The client acknowledges frames.
  std::size_t ack_window_ = kAckWindow;               // Its window (its last ack's).
  bool frame_waiting_ = false;                        // A newer frame exists, unsent.
  bool contacts_on_ = false;                          // The viewer asked for contacts.
  bool contacts_due_ = false;                         // A frame went out since the last.
  std::optional<std::uint64_t> contacts_step_sent_;   // Step of the contacts sent last.
  bool accepted_ = false;
  bool writing_ = false;
  bool closing_ = false;
  bool close_sent_ = false;
  bool finished_ = false;
};

}  // namespace tumble::server
