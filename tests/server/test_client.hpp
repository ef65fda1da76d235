#pragma once
/// A small Beast client for the server tests and the measuring tool: HTTP requests and a
/// WebSocket reader, each operation bounded by a timeout.
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

namespace tumble::server::test {

/// An HTTP response as the tests look at it.
struct HttpReply {
  unsigned status = 0;                       ///< 0 when the request failed.
  std::string body;
  boost::beast::http::fields headers;
  boost::beast::error_code error;            ///< Why status is 0.
  /// The body parsed as JSON (discarded value when it is not JSON).
  nlohmann::json json() const;
};

/// One request on a fresh connection to 127.0.0.1:port (5 s timeout).
HttpReply http_request(std::uint16_t port, boost::beast::http::verb verb, std::string target,
                       std::string body = {},
                       const std::map<std::string, std::string>& headers = {});

/// GET shorthand.
inline HttpReply http_get(std::uint16_t port, std::string target) {
  return http_request(port, boost::beast::http::verb::get, std::move(target));
}
/// POST shorthand.
inline HttpReply http_post(std::uint16_t port, std::string target, std::string body = {},
                           const std::map<std::string, std::string>& headers = {}) {
  return http_request(port, boost::beast::http::verb::post, std::move(target), std::move(body),
                      headers);
}

/// Writes `raw` bytes as they are and reads one HTTP response (5 s timeout).
HttpReply raw_request(std::uint16_t port, const std::string& raw);

/// A viewer that sends the WebSocket upgrade to /ws and then never reads (4 KiB receive
/// buffer): the slow client of the load test and of WsSessionStalled. Blocking connect.
boost::asio::ip::tcp::socket stalled_viewer(boost::asio::io_context& ioc, std::uint16_t port);

/// A WebSocket viewer connected to /ws.
class WsClient {
 public:
  /// A received message.
  struct Message {
    bool text = false;
    std::string data;
    std::chrono::steady_clock::time_point at;
  };

  /// Connects to `target` and completes the handshake; throws boost::system::system_error
  /// on failure (a refused upgrade: boost::beast::websocket::error::upgrade_declined).
  explicit WsClient(std::uint16_t port, const std::string& origin = {},
                    const std::string& target = "/ws");
  /// The next message, or nullopt on timeout, close or error (then see last_error()).
  std::optional<Message> read(std::chrono::milliseconds timeout = std::chrono::seconds(2));
  /// Sends a text message.
  void send_text(const std::string& text);
  /// Why the last read returned nullopt.
  boost::beast::error_code last_error() const { return error_; }

 private:
  boost::asio::io_context ioc_;
  boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
  boost::beast::flat_buffer buffer_;
  boost::beast::error_code error_;
  bool broken_ = false;
};

}  // namespace tumble::server::test
