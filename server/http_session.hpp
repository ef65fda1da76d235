#pragma once
/// One HTTP connection: reads requests (body ≤ 1 MiB, headers ≤ 16 KiB, idle timeout 30 s)
/// and answers with the REST API, static files from the web root, or a WebSocket upgrade at
/// /ws. All its work runs on its own strand (Beast's advanced server).
#include <chrono>
#include <memory>
#include <optional>

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "context.hpp"
#include "rest_api.hpp"

namespace tumble::server {

/// An HTTP/1.1 connection (keep-alive, no pipelining of responses).
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  /// Largest request body, bytes (larger: 413).
  static constexpr std::uint64_t kBodyLimit = 1 << 20;
  /// Largest request header block, bytes (larger: 431).
  static constexpr std::uint32_t kHeaderLimit = 16 * 1024;
  /// A connection idle (or a request unfinished) this long is closed.
  static constexpr std::chrono::seconds kIdleTimeout{30};

  /// Takes over an accepted socket (its executor must be a strand).
  HttpSession(boost::asio::ip::tcp::socket&& socket, ServerContext& ctx);
  /// Starts reading.
  void run();

 private:
  void do_read();
  void on_read(boost::beast::error_code ec, std::size_t bytes);
  void handle(Request&& request);
  void upgrade(Request&& request);
  void serve_file(const Request& request);
  void reply_later(bool head, Response response);
  template <class Body>
  void send(boost::beast::http::response<Body>&& response);
  void on_write(bool close, boost::beast::error_code ec, std::size_t bytes);
  void do_close();
  void do_drain();

  boost::beast::tcp_stream stream_;
  boost::beast::flat_buffer buffer_;
  ServerContext& ctx_;
  std::optional<boost::beast::http::request_parser<boost::beast::http::string_body>> parser_;
  std::shared_ptr<void> response_;  // The response being written.
};

}  // namespace tumble::server
