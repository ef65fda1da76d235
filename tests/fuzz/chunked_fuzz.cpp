// libFuzzer target: the chunked-body path of a request as HttpSession reads it. A fixed
// header (Transfer-Encoding: chunked, the route picked by the second input byte) and then the
// rest of the input as the chunked body (sizes, extensions, data, trailers), fed to a parser
// set up by limit_parser through a read buffer bounded like the session's (kReadBufferLimit),
// in pieces whose size the first input byte picks. It must never need more buffer than the
// limit without reporting it (flat_buffer throws past its maximum: a crash here), never accept
// a body over kBodyLimit or an extension over kChunkExtensionLimit; the header, once read,
// must pass check_framing (as the session checks it, before the body and its trailers), a
// request with trailer fields is refused by check_trailer (as the session does), and any other
// completed request must get exactly one answer from handle_api, errors as JSON.
//
// Boost assertions go to the handler below (BOOST_ENABLE_ASSERT_HANDLER, set for this target
// in CMakeLists.txt): every one traps, but for one known-wrong assertion in Beast 1.81 that
// this target found at once: `n >= 5` in basic_parser::parse_chunk_header, reached when a
// final chunk arrives in pieces ("0\r\n", then "\r", then "\n"). The code after it is
// correct (it asks for more input); upstream relaxed the assertion (boostorg/beast PR #2861,
// merged May 2024). Release builds (NDEBUG) never evaluate it.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>

#include <boost/asio/io_context.hpp>
#include <boost/beast/core/flat_buffer.hpp>
#include <nlohmann/json.hpp>

#include "request_limits.hpp"
#include "rest_api.hpp"
#include "server.hpp"
#include "server_fixture.hpp"
#include "tumble/scene_io.hpp"

namespace boost {

void assertion_failed(char const* expr, char const* function, char const* file, long line) {
  if (std::string_view(expr) == "n >= 5" &&
      std::string_view(file).ends_with("beast/http/impl/basic_parser.ipp"))
    return;
  std::fprintf(stderr, "%s:%ld: %s: Boost assertion '%s' failed\n", file, line, function, expr);
  __builtin_trap();
}

void assertion_failed_msg(char const* expr, char const* msg, char const* function,
                          char const* file, long line) {
  std::fprintf(stderr, "%s:%ld: %s: Boost assertion '%s' failed: %s\n", file, line, function,
               expr, msg);
  __builtin_trap();
}

}  // namespace boost

namespace {

using namespace tumble::server;
namespace http = boost::beast::http;

constexpr const char* kTargets[] = {"/api/step", "/api/reset", "/api/impulse", "/api/pause"};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static fuzz::ServerFixture f;
  if (size < 2) return 0;
  const std::size_t piece = 1 + data[0] % 97;
  const std::string head = std::string("POST ") + kTargets[data[1] % 4] +
                           " HTTP/1.1\r\nHost: fuzz\r\nTransfer-Encoding: chunked\r\n\r\n";
  std::string input = head;
  input.append(reinterpret_cast<const char*>(data + 2), size - 2);

  RequestParser parser;
  limit_parser(parser);
  parser.eager(false);  // the header first, as the session reads it (async_read_header)
  boost::beast::flat_buffer buffer(kReadBufferLimit);
  std::size_t fed = 0;
  boost::beast::error_code ec;
  bool framing_checked = false;
  HeaderFields header = {};
  while (!parser.is_done()) {
    if (fed == input.size()) {
      parser.put_eof(ec);
      break;
    }
    const std::size_t room = buffer.max_size() - buffer.size();
    if (room == 0) return 0;  // The session answers 400 here (http::error::buffer_overflow).
    const std::size_t n = std::min({piece, room, input.size() - fed});
    const auto into = buffer.prepare(n);  // Throws std::length_error past the limit.
    std::memcpy(into.data(), input.data() + fed, n);
    buffer.commit(n);
    fed += n;
    const std::size_t used = parser.put(buffer.data(), ec);
    buffer.consume(used);
    // The session checks the framing once the header is read (HttpSession::on_header), then
    // reads the body: Beast adds the chunked body's trailer fields to the same fields, and a
    // trailer may repeat Host or Content-Length (as an input this target found did), which
    // frames nothing once the body has ended.
    if (!ec && parser.is_header_done() && !framing_checked) {
      if (check_framing(parser.get())) __builtin_trap();  // The fixed header is well framed.
      framing_checked = true;
      header = header_fields(parser.get());
      parser.eager(true);  // then the body as far as the buffer goes
      if (buffer.size() > 0) buffer.consume(parser.put(buffer.data(), ec));
    }
    if (ec == http::error::need_more) {
      ec = {};
      continue;
    }
    if (ec) return 0;
  }
  if (ec || !parser.is_done()) return 0;
  if (check_trailer(parser.get(), header)) return 0;  // The session answers 400 here.
  const Request req = parser.release();
  if (req.body().size() > kBodyLimit) __builtin_trap();
  int answers = 0;
  handle_api(req, f.ctx, [&answers](Response res) {
    ++answers;
    const unsigned status = res.result_int();
    if (status < 100 || status > 599) __builtin_trap();
    if (status >= 400) {
      const auto j = nlohmann::json::parse(res.body(), nullptr, false);
      if (!j.is_object() || !j.contains("error") || !j.contains("field")) __builtin_trap();
    }
  });
  if (answers != 1) __builtin_trap();
  return 0;
}
