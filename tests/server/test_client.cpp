#include "test_client.hpp"

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/write.hpp>

namespace tumble::server::test {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

namespace {

constexpr auto kTimeout = std::chrono::seconds(5);

tcp::endpoint local(std::uint16_t port) { return {net::ip::make_address("127.0.0.1"), port}; }

HttpReply exchange(std::uint16_t port, bool head,
                   const std::function<void(beast::tcp_stream&,
                                            std::function<void(beast::error_code)>)>& write) {
  net::io_context ioc;
  beast::tcp_stream stream(ioc);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.body_limit(64 << 20);
  parser.skip(head);  // A response to HEAD has no body, whatever its Content-Length says.
  HttpReply reply;
  stream.expires_after(kTimeout);
  stream.async_connect(local(port), [&](beast::error_code ec) {
    if (ec) {
      reply.error = ec;
      return;
    }
    write(stream, [&](beast::error_code ec) {
      if (ec) {
        reply.error = ec;
        return;
      }
      http::async_read(stream, buffer, parser, [&](beast::error_code ec, std::size_t) {
        reply.error = ec;
      });
    });
  });
  ioc.run();
  if (!reply.error) {
    auto res = parser.release();
    reply.status = res.result_int();
    reply.body = res.body();
    for (const auto& f : res) reply.headers.set(f.name_string(), f.value());
  }
  return reply;
}

}  // namespace

nlohmann::json HttpReply::json() const {
  return nlohmann::json::parse(body, nullptr, false);
}

HttpReply http_request(std::uint16_t port, http::verb verb, std::string target, std::string body,
                       const std::map<std::string, std::string>& headers) {
  auto req = std::make_shared<http::request<http::string_body>>(verb, target, 11);
  req->set(http::field::host, "127.0.0.1:" + std::to_string(port));
  for (const auto& [k, v] : headers) req->set(k, v);
  req->body() = std::move(body);
  req->prepare_payload();
  return exchange(port, verb == http::verb::head, [req](beast::tcp_stream& s, std::function<void(beast::error_code)> done) {
    http::async_write(s, *req, [req, done](beast::error_code ec, std::size_t) { done(ec); });
  });
}

boost::asio::ip::tcp::socket stalled_viewer(boost::asio::io_context& ioc, std::uint16_t port) {
  namespace net = boost::asio;
  net::ip::tcp::socket socket(ioc);
  socket.open(net::ip::tcp::v4());
  socket.set_option(net::socket_base::receive_buffer_size(4096));
  socket.connect({net::ip::make_address("127.0.0.1"), port});
  net::write(socket, net::buffer(std::string(
                         "GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\n"
                         "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                         "Sec-WebSocket-Version: 13\r\n\r\n")));
  return socket;
}

HttpReply raw_request(std::uint16_t port, const std::string& raw) {
  auto data = std::make_shared<std::string>(raw);
  return exchange(port, raw.starts_with("HEAD "), [data](beast::tcp_stream& s, std::function<void(beast::error_code)> done) {
    net::async_write(s, net::buffer(*data),
                     [data, done](beast::error_code ec, std::size_t) { done(ec); });
  });
}

WsClient::WsClient(std::uint16_t port, const std::string& origin, const std::string& target)
    : ws_(ioc_) {
  beast::get_lowest_layer(ws_).expires_after(kTimeout);
  beast::get_lowest_layer(ws_).connect(local(port));
  beast::get_lowest_layer(ws_).expires_never();
  if (!origin.empty())
    ws_.set_option(websocket::stream_base::decorator(
        [origin](websocket::request_type& req) { req.set(http::field::origin, origin); }));
  ws_.handshake("127.0.0.1:" + std::to_string(port), target);
}

std::optional<WsClient::Message> WsClient::read(std::chrono::milliseconds timeout) {
  if (broken_) return std::nullopt;
  buffer_.clear();
  bool done = false;
  std::size_t bytes = 0;
  error_ = {};
  ws_.async_read(buffer_, [&](beast::error_code ec, std::size_t n) {
    done = true;
    error_ = ec;
    bytes = n;
  });
  ioc_.restart();
  ioc_.run_for(timeout);
  if (!done) {
    beast::get_lowest_layer(ws_).cancel();
    ioc_.restart();
    ioc_.run();
    error_ = net::error::timed_out;
    broken_ = true;  // A cancelled read leaves the stream unusable.
    return std::nullopt;
  }
  if (error_) {
    broken_ = true;
    return std::nullopt;
  }
  return Message{ws_.got_text(), beast::buffers_to_string(buffer_.data()),
                 std::chrono::steady_clock::now()};
}

void WsClient::send_text(const std::string& text) {
  ws_.text(true);
  beast::error_code ec;
  ws_.write(net::buffer(text), ec);
}

}  // namespace tumble::server::test
