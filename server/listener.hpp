#pragma once
/// Accepts TCP connections and gives each an HttpSession on its own strand. Beyond
/// --max-connections a connection gets a canned 503 with Retry-After and is closed. When
/// accept itself fails (out of file descriptors: EMFILE, ENFILE; or memory) it waits
/// kAcceptBackoff before trying again, and logs once per kLogInterval with a count, instead
/// of spinning on the error (and writing a log line per failure).
#include <memory>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core/error.hpp>

#include "context.hpp"

namespace tumble::server {

/// The listening socket.
class Listener : public std::enable_shared_from_this<Listener> {
 public:
  /// Pause after a failed accept.
  static constexpr std::chrono::milliseconds kAcceptBackoff{100};
  /// At most one log line about failed accepts per this interval.
  static constexpr std::chrono::seconds kLogInterval{1};

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
  void back_off(boost::beast::error_code ec);
  void turn_away(boost::asio::ip::tcp::socket& socket);

  boost::asio::io_context& ioc_;
  boost::asio::ip::tcp::acceptor acceptor_;
  ServerContext& ctx_;
  std::uint16_t port_ = 0;
  boost::asio::steady_timer backoff_;  // On the acceptor's strand, as is what follows.
  std::chrono::steady_clock::time_point last_log_{};
  std::uint64_t unlogged_failures_ = 0;
};

}  // namespace tumble::server
