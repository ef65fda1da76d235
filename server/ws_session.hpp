#pragma once
/// One WebSocket viewer (/ws). All its work runs on its own strand. It sends the scene text
/// message first (and again after each reset, before that scene's frames), then binary
/// frames; at most one frame waits: a newer one replaces it and the drop is counted.
/// Client messages are read and ignored (over 4 KiB: the connection is closed). Every half
/// viewer timeout it sends a ping with a random payload; a viewer that has not echoed it in a
/// pong within the timeout (it does not read, or reads too slowly to reach the ping) is
/// dropped, so its slot under --max-viewers is freed.
#include <cstdint>
#include <memory>
#include <string>

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "admission.hpp"
#include "metrics.hpp"
#include "snapshot.hpp"

namespace tumble::server {

class Broadcaster;

/// A WebSocket connection to a viewer.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  /// Largest message a client may send, bytes.
  static constexpr std::size_t kMaxClientMessage = 4096;

  /// Takes over an accepted socket (its executor must be a strand); `timeout`: a ping left
  /// unanswered this long drops the viewer; `slot`: its place under --max-connections.
  WsSession(boost::asio::ip::tcp::socket&& socket, Broadcaster& broadcaster, Metrics& metrics,
            std::chrono::milliseconds timeout = std::chrono::seconds(15),
            ConnectionCount::Slot slot = nullptr);

  /// Completes the upgrade of `request` and starts sending.
  void run(boost::beast::http::request<boost::beast::http::string_body> request);
  /// Queues `frame` (encoded once for everyone) of the scene `scene`. Thread-safe.
  void deliver(std::shared_ptr<const std::string> frame, std::shared_ptr<const SceneInfo> scene);
  /// Closes with a close frame ("going away"). Thread-safe.
  void close();

 private:
  void on_accept(boost::beast::error_code ec);
  void do_read();
  void on_read(boost::beast::error_code ec, std::size_t bytes);
  void on_deliver(std::shared_ptr<const std::string> frame,
                  std::shared_ptr<const SceneInfo> scene);
  void do_write();
  void on_write(bool is_frame, boost::beast::error_code ec, std::size_t bytes);
  void do_close();
  void finish();
  void do_ping_timer();
  void on_ping_timer(boost::beast::error_code ec);
  void drop();

  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
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
  std::shared_ptr<const std::string> pending_frame_;  // The one waiting frame.
  std::shared_ptr<const std::string> in_flight_;      // Kept alive while being written.
  std::uint64_t generation_ = 0;                      // Scene generation queued last.
  bool accepted_ = false;
  bool writing_ = false;
  bool closing_ = false;
  bool close_sent_ = false;
  bool finished_ = false;
};

}  // namespace tumble::server
