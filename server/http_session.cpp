#include "http_session.hpp"

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/websocket.hpp>

#include <cstdio>
#include <new>

#include "log.hpp"
#include "static_cache.hpp"
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

// An error that ends the connection: answered before (or instead of) reading the request's
// body, so nothing after it on the connection may be read as another request.
Response closing_error(unsigned status, std::string_view message, std::string_view field) {
  Response res{static_cast<http::status>(status), 11};
  res.set(http::field::content_type, "application/json");
  res.keep_alive(false);
  res.body() = nlohmann::json{{"error", message}, {"field", field}}.dump();
  res.prepare_payload();
  return res;
}

// RFC 6455 §4.1: the key is the base64 of 16 bytes: 22 alphabet characters, the last of which
// carries 2 bits and 4 zero bits (so one of A, Q, g, w), then "==".
bool valid_websocket_key(std::string_view key) {
  while (!key.empty() && (key.front() == ' ' || key.front() == '\t')) key.remove_prefix(1);
  while (!key.empty() && (key.back() == ' ' || key.back() == '\t')) key.remove_suffix(1);
  if (key.size() != 24 || key.substr(22) != "==") return false;
  for (std::size_t i = 0; i < 22; ++i) {
    const char c = key[i];
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '+' && c != '/') return false;
  }
  return std::string_view("AQgw").find(key[21]) != std::string_view::npos;
}

// `text` with %XX escapes and '+' (form encoding, as URLSearchParams writes a space) decoded;
// a malformed escape is kept as it is (it then matches no token).
std::string form_decode(std::string_view text) {
  const auto hex = [](char c) {
    return std::isxdigit(static_cast<unsigned char>(c))
               ? (std::isdigit(static_cast<unsigned char>(c)) ? c - '0' : (c | 0x20) - 'a' + 10)
               : -1;
  };
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '+') {
      out += ' ';
    } else if (text[i] == '%' && i + 2 < text.size() && hex(text[i + 1]) >= 0 &&
               hex(text[i + 2]) >= 0) {
      out += static_cast<char>(hex(text[i + 1]) * 16 + hex(text[i + 2]));
      i += 2;
    } else {
      out += text[i];
    }
  }
  return out;
}

// The query parameter `name` of `target` (still encoded), "" when absent.
std::string_view query_parameter(std::string_view target, std::string_view name) {
  const std::size_t q = target.find('?');
  if (q == std::string_view::npos) return {};
  std::string_view query = target.substr(q + 1);
  while (!query.empty()) {
    const std::size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    if (pair.size() > name.size() && pair.starts_with(name) && pair[name.size()] == '=')
      return pair.substr(name.size() + 1);
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return {};
}

bool costly_read(const Request& req) {
  if (req.method() != http::verb::get && req.method() != http::verb::head) return false;
  const std::string_view target = req.target();
  const std::string_view path = target.substr(0, target.find_first_of("?#"));
  return path.ends_with("/state") || path.ends_with("/scene") || path.ends_with("/recording");
}

}  // namespace

HttpSession::HttpSession(net::ip::tcp::socket&& socket, ServerContext& ctx,
                         ConnectionCount::Slot slot)
    : stream_(std::move(socket)),
      refusal_delay_(stream_.get_executor()),
      ctx_(ctx),
      slot_(std::move(slot)) {
  beast::error_code ec;
  const auto peer = stream_.socket().remote_endpoint(ec);
  if (!ec) client_ = peer.address().to_string();
}

void HttpSession::run() {
  net::dispatch(stream_.get_executor(),
                beast::bind_front_handler(&HttpSession::do_read, shared_from_this()));
}

void HttpSession::do_read() {
  parser_.emplace();
  limit_parser(*parser_);
  stream_.expires_after(kIdleTimeout);
  http::async_read_header(stream_, buffer_, *parser_,
                          beast::bind_front_handler(&HttpSession::on_header, shared_from_this()));
}

// The header is checked before any body is read: a refused framing is answered and the
// connection closed, so the body can never be parsed as a request of its own.
void HttpSession::on_header(beast::error_code ec, std::size_t) {
  if (ec) return on_read_error(ec);
  const auto& header = parser_->get();
  if (const std::optional<FramingRefusal> r = check_framing(header))
    return refuse(r->status, r->message, r->field);
  header_fields_.clear();
  if (parser_->chunked()) header_fields_ = header_fields(header);
  if (parser_->is_done()) return on_read({}, 0);
  if (!expects_continue(header)) return do_read_body();
  static constexpr std::string_view kContinue = "HTTP/1.1 100 Continue\r\n\r\n";
  net::async_write(stream_, net::buffer(kContinue.data(), kContinue.size()),
                   [self = shared_from_this()](beast::error_code ec, std::size_t) {
                     if (ec) return self->do_close();
                     self->do_read_body();
                   });
}

void HttpSession::do_read_body() {
  http::async_read(stream_, buffer_, *parser_,
                   beast::bind_front_handler(&HttpSession::on_read, shared_from_this()));
}

void HttpSession::on_read(beast::error_code ec, std::size_t) {
  if (ec) return on_read_error(ec);
  if (parser_->chunked())
    if (const std::optional<FramingRefusal> r = check_trailer(parser_->get(), header_fields_))
      return refuse(r->status, r->message, r->field);
  try {
    handle(parser_->release());
  } catch (const std::exception& e) {  // e.g. std::bad_alloc: this connection ends, not the server.
    std::fprintf(stderr, "tumble-server: request handling: %s (connection closed)\n", e.what());
    do_close();
  }
}

void HttpSession::on_read_error(beast::error_code ec) {
  if (ec == http::error::end_of_stream) return do_close();
  if (ec == http::error::body_limit) return refuse(413, "request body over 1 MiB", "");
  if (ec == http::error::header_limit) return refuse(431, "request headers too large", "");
  if (ec == http::error::buffer_overflow)
    return refuse(400, "request metadata (chunk header or trailer) over 32 KiB", "");
  if (ec == http::error::bad_chunk_extension)
    return refuse(400, "chunk extension malformed or over 256 bytes", "");
  if (ec == net::error::operation_aborted || ec == beast::error::timeout ||
      ec == net::error::eof || ec == net::error::connection_reset)
    return do_close();
  if (ec.category() == http::make_error_code(http::error::bad_target).category())
    return refuse(400, "malformed HTTP request", "");
  fail(ec, "http read");
  do_close();
}

void HttpSession::refuse(unsigned status, std::string_view message, std::string_view field) {
  send(closing_error(status, message, field));
}

void HttpSession::handle(Request&& req) {
  if (beast::websocket::is_upgrade(req)) return upgrade(std::move(req));
  if (is_api_target(req.target())) {
    const bool head = req.method() == http::verb::head;
    const std::shared_ptr<HostedWorld> world =
        costly_read(req) ? world_of_target(req.target(), ctx_) : nullptr;
    if (world) {
      const double cost = 1.0 + static_cast<double>(world->sim().latest()->bodies->size());
      if (const int wait = ctx_.read_budget.admit(client_, cost)) {
        Response res = error_response(req, 429, "read budget of this client spent", "");
        res.set(http::field::retry_after, std::to_string(wait));
        refusal_delay_.expires_after(kRefusalDelay);
        refusal_delay_.async_wait([self = shared_from_this(), head,
                                   res = std::move(res)](beast::error_code) mutable {
          self->reply_later(head, std::move(res));
        });
        return;
      }
    }
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
    try {
      if (!head) return self->send(std::move(res));
      http::response<http::empty_body> bare{res.result(), res.version()};
      for (const auto& field : res) bare.set(field.name_string(), field.value());
      bare.keep_alive(res.keep_alive());
      self->send(std::move(bare));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "tumble-server: reply: %s (connection closed)\n", e.what());
      self->do_close();
    }
  });
}

void HttpSession::upgrade(Request&& req) {
  const std::string_view path = req.target().substr(0, req.target().find('?'));
  if (path != "/ws") return send(error_response(req, 404, "no WebSocket at this path", ""));
  if (!valid_websocket_key(req[http::field::sec_websocket_key]))
    return refuse(400, "Sec-WebSocket-Key must be the base64 of 16 bytes", "Sec-WebSocket-Key");
  if (!origin_allowed(req, ctx_.options))
    return send(error_response(req, 403, "WebSocket from this origin is not allowed", "Origin"));
  if (ctx_.options.token_reads && !authorised(req, ctx_.options) &&
      !token_matches(form_decode(query_parameter(req.target(), "access_token")),
                     ctx_.options.token))
    return send(error_response(req, 401, "missing or wrong token", "Authorization"));
  const std::string id = form_decode(query_parameter(req.target(), "world"));
  const std::shared_ptr<HostedWorld> world =
      ctx_.worlds.find(id.empty() ? std::string(kDefaultWorld) : id);
  if (!world)
    return send(error_response(req, 404, "no world '" + quoted_prefix(id) + "'", "world"));
  if (world->broadcaster().viewers() >= static_cast<std::size_t>(ctx_.options.max_viewers))
    return send(error_response(req, 503, "too many viewers", ""));
  world->touch();
  stream_.expires_never();
  std::make_shared<WsSession>(stream_.release_socket(), world->broadcaster(), ctx_.metrics,
                              std::chrono::milliseconds(ctx_.options.viewer_timeout_ms),
                              std::move(slot_), world)
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
  StaticLookup found = resolve_static(ctx_.web_root, req.target());
  beast::file file;
  if (found.status == 200) {
    const OpenedFile opened = open_beneath(ctx_.web_root_fd, found.relative);
    found.status = opened.status;
    if (opened.fd >= 0) file.native_handle(opened.fd);
  }
  if (found.status != 200) {
    const char* why = found.status == 403   ? "path refused"
                      : found.status == 400 ? "malformed path"
                                            : "not found";
    return send(error_response(req, found.status, why, ""));
  }
  send_file(req, std::move(file), found);
}

// Static files are revalidated on every use (no-cache) but cheaply: a current copy gets 304
// and no body. Text files go gzip-compressed to clients that accept it (made once per file
// version, StaticCache), with the variant's own ETag.
void HttpSession::send_file(const Request& req, beast::file file, const StaticLookup& found) {
  struct stat st {};
  if (::fstat(file.native_handle(), &st) != 0) return send(error_response(req, 404, "not found", ""));
  const std::string_view type = mime_type(found.file);
  const bool gzip = compressible(type) &&
                    accepts_gzip(req[http::field::accept_encoding]) &&
                    static_cast<std::size_t>(st.st_size) <= StaticCache::kMaxFile;
  const std::string identity_tag = file_etag(st);
  const std::string gzip_tag = identity_tag.substr(0, identity_tag.size() - 1) + "-gz\"";
  const std::string_view if_none_match = req[http::field::if_none_match];
  const auto headers = [&](auto& res, const std::string& etag) {
    // A 304 carries no representation metadata (RFC 9110 §15.4.5): the client keeps the
    // cached copy's Content-Type. A repeat visit of the page revalidates ~26 files, and the
    // header was ~1.2 KB of its 10 KB.
    if (res.result() != http::status::not_modified) res.set(http::field::content_type, type);
    res.set(http::field::cache_control, "no-cache");
    res.set(http::field::etag, etag);
    // Cross-origin isolation: the page may then share memory with its stream worker.
    res.set("Cross-Origin-Opener-Policy", "same-origin");
    res.set("Cross-Origin-Embedder-Policy", "require-corp");
    if (compressible(type)) res.set(http::field::vary, "Accept-Encoding");
    res.keep_alive(req.keep_alive());
  };
  if (etag_matches(if_none_match, identity_tag) || etag_matches(if_none_match, gzip_tag)) {
    http::response<http::empty_body> res{http::status::not_modified, req.version()};
    headers(res, gzip ? gzip_tag : identity_tag);
    return send(std::move(res));
  }
  std::shared_ptr<const std::string> packed;
  if (gzip) packed = ctx_.static_cache.gzip(found.relative.string(), file.native_handle(), st);
  const std::uint64_t size = packed ? packed->size() : static_cast<std::uint64_t>(st.st_size);
  if (req.method() == http::verb::head) {
    http::response<http::empty_body> res{http::status::ok, req.version()};
    headers(res, packed ? gzip_tag : identity_tag);
    if (packed) res.set(http::field::content_encoding, "gzip");
    res.content_length(size);
    return send(std::move(res));
  }
  if (packed) {
    http::response<http::string_body> res{http::status::ok, req.version()};
    headers(res, gzip_tag);
    res.set(http::field::content_encoding, "gzip");
    res.body() = *packed;
    res.content_length(size);
    return send(std::move(res));
  }
  beast::error_code ec;
  http::file_body::value_type body;
  body.reset(std::move(file), ec);
  if (ec) return send(error_response(req, 404, "not found", ""));
  http::response<http::file_body> res{std::piecewise_construct, std::make_tuple(std::move(body)),
                                      std::make_tuple(http::status::ok, req.version())};
  headers(res, identity_tag);
  res.content_length(size);
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
  stream_.async_read_some(buffer_.prepare(buffer_.max_size()),
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
