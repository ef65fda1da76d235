// libFuzzer target: arbitrary bytes as an HTTP request, through Beast's parser (with the
// server's limits) and then the server's own request handling, without sockets: the REST
// routes (handle_api, on a simulation that is built but stopped, so every command answers
// 503 after its request was parsed and validated) and the static-file resolver. Every
// request must get exactly one answer with a 1xx–5xx status and, for errors, the JSON body
// {"error", "field"}; nothing may throw.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>

#include <boost/asio/io_context.hpp>
#include <boost/beast/http.hpp>
#include <nlohmann/json.hpp>

#include "request_limits.hpp"
#include "rest_api.hpp"
#include "server.hpp"
#include "server_fixture.hpp"
#include "static_files.hpp"
#include "tumble/scene_io.hpp"

namespace {

using namespace tumble::server;
namespace http = boost::beast::http;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static fuzz::ServerFixture f("fuzz-token", "http://viewer.example");
  RequestParser parser;
  limit_parser(parser);
  parser.eager(true);
  boost::beast::error_code ec;
  parser.put(boost::asio::buffer(data, size), ec);
  if (!ec && !parser.is_done()) parser.put_eof(ec);
  if (ec || !parser.is_done()) return 0;
  const Request req = parser.release();
  if (!is_api_target(req.target())) {
    const StaticLookup found = resolve_static(f.ctx.web_root, req.target());
    if (found.status != 200 && found.status != 400 && found.status != 403 &&
        found.status != 404)
      __builtin_trap();
    return 0;
  }
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
