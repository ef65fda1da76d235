#include "listener.hpp"

#include <boost/asio/post.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>

#include <cstdio>

#include "http_session.hpp"
#include "log.hpp"

namespace tumble::server {

namespace net = boost::asio;
namespace beast = boost::beast;
using tcp = net::ip::tcp;

Listener::Listener(net::io_context& ioc, const tcp::endpoint& endpoint, ServerContext& ctx)
    : ioc_(ioc), acceptor_(net::make_strand(ioc)), ctx_(ctx), backoff_(acceptor_.get_executor()) {
  acceptor_.open(endpoint.protocol());
  acceptor_.set_option(net::socket_base::reuse_address(true));
  acceptor_.bind(endpoint);
  acceptor_.listen(net::socket_base::max_listen_connections);
  port_ = acceptor_.local_endpoint().port();
}

void Listener::run() {
  net::post(acceptor_.get_executor(), [self = shared_from_this()] { self->do_accept(); });
}

void Listener::stop() {
  net::post(acceptor_.get_executor(), [self = shared_from_this()] {
    beast::error_code ec;
    self->acceptor_.close(ec);
    self->backoff_.cancel();
  });
}

void Listener::do_accept() {
  acceptor_.async_accept(net::make_strand(ioc_),
                         beast::bind_front_handler(&Listener::on_accept, shared_from_this()));
}

void Listener::on_accept(beast::error_code ec, tcp::socket socket) {
  if (ec == net::error::operation_aborted || !acceptor_.is_open()) return;
  if (ec) return back_off(ec);
  try {
    if (ConnectionCount::Slot slot = ctx_.connections.try_acquire())
      std::make_shared<HttpSession>(std::move(socket), ctx_, std::move(slot))->run();
    else
      turn_away(socket);
  } catch (const std::exception& e) {  // e.g. std::bad_alloc: drop this connection only.
    std::fprintf(stderr, "tumble-server: accept: %s (connection closed)\n", e.what());
  }
  do_accept();
}

// Accepting again at once after EMFILE fails again at once: the pending connection stays in
// the backlog and the loop spins. Wait, so that sessions can end and free descriptors.
void Listener::back_off(beast::error_code ec) {
  ++unlogged_failures_;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_log_ >= kLogInterval) {
    std::fprintf(stderr, "tumble-server: accept: %s (%llu failures; retrying every %lld ms)\n",
                 ec.message().c_str(), static_cast<unsigned long long>(unlogged_failures_),
                 static_cast<long long>(kAcceptBackoff.count()));
    last_log_ = now;
    unlogged_failures_ = 0;
  }
  backoff_.expires_after(kAcceptBackoff);
  backoff_.async_wait([self = shared_from_this()](beast::error_code ec) {
    if (ec || !self->acceptor_.is_open()) return;
    self->do_accept();
  });
}

// Over --max-connections: a fixed answer written without waiting (a full socket buffer just
// loses it), then closed; no session, no buffer, no timer is spent on it.
void Listener::turn_away(tcp::socket& socket) {
  static constexpr std::string_view kBusy =
      "HTTP/1.1 503 Service Unavailable\r\nServer: tumble-server\r\n"
      "Content-Type: application/json\r\nRetry-After: 1\r\nConnection: close\r\n"
      "Content-Length: 46\r\n\r\n{\"error\": \"too many connections\", \"field\": \"\"}";
  beast::error_code ec;
  socket.non_blocking(true, ec);
  socket.write_some(net::buffer(kBusy.data(), kBusy.size()), ec);
  socket.shutdown(tcp::socket::shutdown_send, ec);
  socket.close(ec);
}

}  // namespace tumble::server
