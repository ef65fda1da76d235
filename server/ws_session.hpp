#pragma once
/// One WebSocket viewer (/ws). All its work runs on its own strand. It sends the scene text
/// message first (and again after each reset, before that scene's frames), then binary
/// frames; at most one frame waits: a newer one replaces it and the drop is counted.
/// Client messages are read and ignored (over 4 KiB: the connection is closed).
#include <cstdint>
#include <memory>
#include <string>

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "metrics.hpp"
#include "snapshot.hpp"

namespace tumble::server {

class Broadcaster;

/// A WebSocket connection to a viewer.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  /// Largest message a client may send, bytes.
  static constexpr std::size_t kMaxClientMessage = 4096;

  /// Takes over an accepted socket (its executor must be a strand).
  WsSession(boost::asio::ip::tcp::socket&& socket, Broadcaster& broadcaster, Metrics& metrics);

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

  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  Broadcaster& broadcaster_;
  Metrics& metrics_;
  boost::beast::flat_buffer read_buffer_;
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
