#include "http_session.hpp"

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/websocket.hpp>

#include "log.hpp"
#include "static_files.hpp"
#include "ws_session.hpp"

namespace tumble::server {

namespace beast = boost::beast;
namespace http = beast::http;
namespace net = boost::asio;

namespace {

template <class Body>
void common_headers(http::response<Body>& res) {
  res.set(http::field::server, "tumble-server");
  res.set("X-Content-Type-Options", "nosniff");
}

// A bare error answered before a request could be parsed (no request to mirror).
Response early_error(unsigned status, std::string_view message) {
  Response res{static_cast<http::status>(status), 11};
  res.set(http::field::content_type, "application/json");
  res.keep_alive(false);
  res.body() = nlohmann::json{{"error", message}, {"field", ""}}.dump();
  res.prepare_payload();
  return res;
}

}  // namespace

HttpSession::HttpSession(net::ip::tcp::socket&& socket, ServerContext& ctx)
    : stream_(std::move(socket)), ctx_(ctx) {}

void HttpSession::run() {
  net::dispatch(stream_.get_executor(),
                beast::bind_front_handler(&HttpSession::do_read, shared_from_this()));
}

void HttpSession::do_read() {
  parser_.emplace();
  parser_->body_limit(kBodyLimit);
  parser_->header_limit(kHeaderLimit);
  stream_.expires_after(kIdleTimeout);
  http::async_read(stream_, buffer_, *parser_,
                   beast::bind_front_handler(&HttpSession::on_read, shared_from_this()));
}

void HttpSession::on_read(beast::error_code ec, std::size_t) {
  if (ec == http::error::end_of_stream) return do_close();
  if (ec == http::error::body_limit)
    return send(early_error(413, "request body over 1 MiB"));
  if (ec == http::error::header_limit)
    return send(early_error(431, "request headers too large"));
  if (ec == net::error::operation_aborted || ec == beast::error::timeout ||
      ec == net::error::eof || ec == net::error::connection_reset)
    return do_close();
  if (ec && ec.category() == http::make_error_code(http::error::bad_target).category())
    return send(early_error(400, "malformed HTTP request"));
  if (ec) {
    fail(ec, "http read");
    return do_close();
  }
  handle(parser_->release());
}

void HttpSession::handle(Request&& req) {
  if (beast::websocket::is_upgrade(req)) return upgrade(std::move(req));
  if (is_api_target(req.target())) {
    const bool head = req.method() == http::verb::head;
    handle_api(req, ctx_, [self = shared_from_this(), head](Response res) {
      self->reply_later(head, std::move(res));
    });
    return;
  }
  serve_file(req);
}

// A reply may come from the simulation thread: continue on this session's strand.
void HttpSession::reply_later(bool head, Response res) {
  net::post(stream_.get_executor(), [self = shared_from_this(), head,
                                     res = std::move(res)]() mutable {
    if (!head) return self->send(std::move(res));
    http::response<http::empty_body> bare{res.result(), res.version()};
    for (const auto& field : res) bare.set(field.name_string(), field.value());
    bare.keep_alive(res.keep_alive());
    self->send(std::move(bare));
  });
}

void HttpSession::upgrade(Request&& req) {
  const std::string_view path = req.target().substr(0, req.target().find('?'));
  if (path != "/ws") return send(error_response(req, 404, "no WebSocket at this path", ""));
  if (!origin_allowed(req, ctx_.options))
    return send(error_response(req, 403, "WebSocket from this origin is not allowed", "Origin"));
  if (ctx_.broadcaster.viewers() >= static_cast<std::size_t>(ctx_.options.max_viewers))
    return send(error_response(req, 503, "too many viewers", ""));
  stream_.expires_never();
  std::make_shared<WsSession>(stream_.release_socket(), ctx_.broadcaster, ctx_.metrics)
      ->run(std::move(req));
}

void HttpSession::serve_file(const Request& req) {
  if (req.method() != http::verb::get && req.method() != http::verb::head) {
    Response res = error_response(req, 405, "method not allowed", "");
    res.set(http::field::allow, "GET, HEAD");
    return send(std::move(res));
  }
  if (req.target().substr(0, req.target().find('?')) == "/ws")
    return send(error_response(req, 426, "use a WebSocket upgrade at /ws", ""));
  const StaticLookup found = resolve_static(ctx_.web_root, req.target());
  if (found.status != 200) {
    const char* why = found.status == 403   ? "path refused"
                      : found.status == 400 ? "malformed path"
                                            : "not found";
    return send(error_response(req, found.status, why, ""));
  }
  beast::error_code ec;
  http::file_body::value_type file;
  file.open(found.file.c_str(), beast::file_mode::scan, ec);
  if (ec) return send(error_response(req, 404, "not found", ""));
  const std::uint64_t size = file.size();
  const std::string_view type = mime_type(found.file);
  if (req.method() == http::verb::head) {
    http::response<http::empty_body> res{http::status::ok, req.version()};
    res.set(http::field::content_type, type);
    res.set(http::field::cache_control, "no-cache");
    res.content_length(size);
    res.keep_alive(req.keep_alive());
    return send(std::move(res));
  }
  http::response<http::file_body> res{std::piecewise_construct, std::make_tuple(std::move(file)),
                                      std::make_tuple(http::status::ok, req.version())};
  res.set(http::field::content_type, type);
  res.set(http::field::cache_control, "no-cache");
  res.content_length(size);
  res.keep_alive(req.keep_alive());
  send(std::move(res));
}

template <class Body>
void HttpSession::send(http::response<Body>&& response) {
  common_headers(response);
  ctx_.metrics.count_http(response.result_int());
  auto res = std::make_shared<http::response<Body>>(std::move(response));
  response_ = res;
  stream_.expires_after(kIdleTimeout);
  http::async_write(stream_, *res,
                    beast::bind_front_handler(&HttpSession::on_write, shared_from_this(),
                                              res->need_eof()));
}

void HttpSession::on_write(bool close, beast::error_code ec, std::size_t) {
  response_.reset();
  if (ec) {
    fail(ec, "http write");
    return do_close();
  }
  if (!close) return do_read();
  // A request we refused may still be arriving: stop sending, then read and discard what
  // is left for a short while, so that the client sees our answer rather than a reset.
  stream_.socket().shutdown(net::ip::tcp::socket::shutdown_send, ec);
  stream_.expires_after(std::chrono::seconds(2));
  do_drain();
}

void HttpSession::do_drain() {
  buffer_.consume(buffer_.size());
  stream_.async_read_some(buffer_.prepare(64 * 1024),
                          [self = shared_from_this()](beast::error_code ec, std::size_t) {
                            if (ec) return self->do_close();
                            self->do_drain();
                          });
}

void HttpSession::do_close() {
  beast::error_code ec;
  stream_.socket().shutdown(net::ip::tcp::socket::shutdown_both, ec);
  stream_.socket().close(ec);
}

}  // namespace tumble::server
