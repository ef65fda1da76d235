#pragma once
/// Accepts TCP connections and gives each an HttpSession on its own strand.
#include <memory>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core/error.hpp>

#include "context.hpp"

namespace tumble::server {

/// The listening socket.
class Listener : public std::enable_shared_from_this<Listener> {
 public:
  /// Opens, binds and listens; throws boost::system::system_error (e.g. address in use).
  Listener(boost::asio::io_context& ioc, const boost::asio::ip::tcp::endpoint& endpoint,
           ServerContext& ctx);
  /// Starts accepting.
  void run();
  /// Stops accepting (thread-safe).
  void stop();
  /// The bound port (useful after binding port 0).
  std::uint16_t port() const { return port_; }

 private:
  void do_accept();
  void on_accept(boost::beast::error_code ec, boost::asio::ip::tcp::socket socket);

  boost::asio::io_context& ioc_;
  boost::asio::ip::tcp::acceptor acceptor_;
  ServerContext& ctx_;
  std::uint16_t port_ = 0;
};

}  // namespace tumble::server
