#include "log.hpp"

#include <boost/asio/error.hpp>
#include <boost/beast/http/error.hpp>
#include <boost/beast/websocket/error.hpp>

#include <cstdio>

namespace tumble::server {

namespace net = boost::asio;
namespace beast = boost::beast;

bool is_normal_end(beast::error_code ec) {
  return !ec || ec == beast::websocket::error::closed || ec == net::error::operation_aborted ||
         ec == net::error::eof || ec == net::error::connection_reset ||
         ec == net::error::broken_pipe || ec == net::error::not_connected ||
         ec == beast::error::timeout || ec == beast::http::error::end_of_stream ||
         ec == beast::websocket::error::message_too_big;  // The client's fault, not ours.
}

void fail(beast::error_code ec, const char* what) {
  if (is_normal_end(ec)) return;
  std::fprintf(stderr, "tumble-server: %s: %s\n", what, ec.message().c_str());
}

}  // namespace tumble::server
