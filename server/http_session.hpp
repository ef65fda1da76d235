#pragma once
/// One HTTP connection: reads requests within the limits of request_limits.hpp (body ≤ 1 MiB,
/// headers ≤ 16 KiB, read buffer ≤ 32 KiB, idle timeout 30 s), checks their framing on the
/// header before any body is read, and answers with the REST API, static files from the web
/// root, or a WebSocket upgrade at /ws. All its work runs on its own strand (Beast's
/// advanced server); no handler lets an exception reach Asio.
#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>

#include "context.hpp"
#include "request_limits.hpp"
#include "rest_api.hpp"
#include "static_files.hpp"

namespace tumble::server {

/// An HTTP/1.1 connection (keep-alive, no pipelining of responses).
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  /// Largest request body, bytes (larger: 413).
  static constexpr std::uint64_t kBodyLimit = tumble::server::kBodyLimit;
  /// Largest request header block, bytes (larger: 431).
  static constexpr std::uint32_t kHeaderLimit = tumble::server::kHeaderLimit;
  /// A connection idle (or a request unfinished) this long is closed.
  static constexpr std::chrono::seconds kIdleTimeout{30};
  /// A 429 (read budget spent) is answered this much later: a client looping on its 429s
  /// without honouring Retry-After gets 10 answers a second per connection, not thousands.
  static constexpr std::chrono::milliseconds kRefusalDelay{100};

  /// Takes over an accepted socket (its executor must be a strand) and the connection's
  /// place under --max-connections (released when the session, or its WebSocket, ends).
  HttpSession(boost::asio::ip::tcp::socket&& socket, ServerContext& ctx,
              ConnectionCount::Slot slot);
  /// Starts reading.
  void run();

 private:
  void do_read();
  void on_header(boost::beast::error_code ec, std::size_t bytes);
  void do_read_body();
  void on_read(boost::beast::error_code ec, std::size_t bytes);
  void on_read_error(boost::beast::error_code ec);
  void refuse(unsigned status, std::string_view message, std::string_view field);
  void handle(Request&& request);
  void upgrade(Request&& request);
  void serve_file(const Request& request);
  void send_file(const Request& request, boost::beast::file file, const StaticLookup& found);
  void reply_later(bool head, Response response);
  template <class Body>
  void send(boost::beast::http::response<Body>&& response);
  void on_write(bool close, boost::beast::error_code ec, std::size_t bytes);
  void do_close();
  void do_drain();

  boost::beast::tcp_stream stream_;
  boost::beast::flat_buffer buffer_{kReadBufferLimit};
  boost::asio::steady_timer refusal_delay_;
  ServerContext& ctx_;
  ConnectionCount::Slot slot_;
  std::string client_;  // The peer's address (the key of its read budget).
  std::optional<RequestParser> parser_;
  HeaderFields header_fields_;  // the chunked request's header fields (to refuse a trailer)
  std::shared_ptr<void> response_;  // The response being written.
};

}  // namespace tumble::server
