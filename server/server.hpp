#pragma once
/// The whole server in one object, so that main and the tests start it the same way.
///
/// Usage:
///   tumble::server::Server server(options, tumble::load_scene(options.scene));
///   server.start();                 // throws boost::system::system_error if it cannot bind
///   std::cout << server.url();      // "http://127.0.0.1:8080/"
///   …
///   server.stop();                  // closes every WebSocket with a close frame, ≤ ~1 s
#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/io_context.hpp>

#include "admission.hpp"
#include "context.hpp"
#include "metrics.hpp"
#include "options.hpp"
#include "sim_pool.hpp"
#include "worlds.hpp"

namespace tumble::server {

class Listener;

/// io_context + I/O threads, the simulation threads, the worlds and the listener.
class Server {
 public:
  /// Builds everything (throws tumble::InvalidInput for an invalid scene); nothing runs yet.
  Server(ServerOptions options, Scene scene);
  /// Stops if still running.
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Binds and starts the threads; throws boost::system::system_error when it cannot bind.
  void start();
  /// Graceful stop: no new connections, close frames to every viewer (waits ≤ 0.5 s for
  /// them), then the simulation and I/O threads end. Idempotent; thread-safe.
  void stop();

  /// The bound port.
  std::uint16_t port() const;
  /// The viewer's URL, e.g. "http://127.0.0.1:8080/".
  std::string url() const;
  /// The default world's simulation (for tests).
  SimLoop& sim() { return worlds_.default_world()->sim(); }
  /// The metrics (for tests).
  const Metrics& metrics() const { return metrics_; }
  /// Connected viewers, all worlds.
  std::size_t viewers() const { return worlds_.viewers(); }
  /// The default world's broadcaster (its frame store, for tests).
  Broadcaster& broadcaster() { return worlds_.default_world()->broadcaster(); }
  /// The worlds (for tests).
  WorldRegistry& worlds() { return worlds_; }
  /// Open connections (HTTP and WebSocket).
  std::size_t connections() const { return connections_.open(); }
  /// The I/O context (for tests that post work to the I/O threads).
  boost::asio::io_context& io_context() { return ioc_; }

 private:
  void run_io();

  // Destruction runs bottom-up: the listener and the worlds (timers) go before the
  // io_context, whose destruction frees the sessions; the pool outlives every world's loop
  // (stop() takes them out of it).
  ServerOptions options_;
  Metrics metrics_;
  ConnectionCount connections_;
  ReadBudget read_budget_;
  StaticCache static_cache_;
  int web_root_fd_ = -1;
  SimPool pool_;
  boost::asio::io_context ioc_;
  WorldRegistry worlds_;
  ServerContext ctx_;
  std::shared_ptr<Listener> listener_;
  std::optional<boost::asio::executor_work_guard<boost::asio::io_context::executor_type>> work_;
  std::vector<std::thread> threads_;
  std::atomic<bool> stopped_{false};
};

}  // namespace tumble::server
