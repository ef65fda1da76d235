#include "server.hpp"

#include <boost/asio/ip/address.hpp>
#include <boost/asio/post.hpp>

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>

#include "listener.hpp"

namespace tumble::server {

namespace net = boost::asio;

namespace {

std::filesystem::path canonical_root(const std::filesystem::path& root) {
  std::error_code ec;
  std::filesystem::path p = std::filesystem::canonical(root, ec);
  if (ec) {
    std::fprintf(stderr, "tumble-server: warning: web root %s: %s (static files will 404)\n",
                 root.string().c_str(), ec.message().c_str());
    return std::filesystem::absolute(root, ec);
  }
  return p;
}

// The directory static files are opened beneath (openat2 RESOLVE_BENEATH); -1: none.
int open_root(const std::filesystem::path& root) {
  return ::open(root.c_str(), O_PATH | O_DIRECTORY | O_CLOEXEC);
}

// The simulation is the product and must keep real time; an I/O thread that waits only makes
// a viewer's frame or a REST answer a little later. So on a loaded machine the I/O threads
// yield to the simulation threads: Linux gives each thread its own nice value (setpriority on
// its thread id), and raising one's own needs no privilege. Measured with
// `server_load --profile stream` (200 viewers of the landing pile, 2 cores): docs/benchmarks.md.
void lower_priority(int nice) {
  if (nice > 0) ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()), nice);
}

}  // namespace

Server::Server(ServerOptions options, Scene scene)
    : options_(std::move(options)),
      connections_(static_cast<std::size_t>(options_.max_connections)),
      read_budget_(options_.read_budget, options_.read_budget),
      pool_(options_.sim_threads > 0 ? static_cast<unsigned>(options_.sim_threads)
                                     : World::hardware_threads()),
      ioc_(options_.threads),
      worlds_(ioc_, pool_, metrics_, options_, std::move(scene)),
      ctx_{options_,     canonical_root(options_.web_root), worlds_, metrics_, connections_,
           read_budget_, static_cache_} {
  ctx_.web_root_fd = web_root_fd_ = open_root(ctx_.web_root);
}

Server::~Server() {
  stop();
  if (web_root_fd_ >= 0) ::close(web_root_fd_);
}

void Server::start() {
  const net::ip::tcp::endpoint endpoint(net::ip::make_address(options_.bind), options_.port);
  listener_ = std::make_shared<Listener>(ioc_, endpoint, ctx_);
  work_.emplace(ioc_.get_executor());
  listener_->run();
  worlds_.start();
  for (int i = 0; i < options_.threads; ++i) threads_.emplace_back([this] { run_io(); });
}

void Server::stop() {
  if (stopped_.exchange(true)) return;
  if (listener_) listener_->stop();
  worlds_.stop();  // Every loop leaves the pool; viewers get close frames.
  if (listener_) {
    // Viewers answer the close frame; give them a moment, then cut what is left.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
    while (worlds_.viewers() > 0 && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  work_.reset();
  ioc_.stop();
  for (std::thread& t : threads_) t.join();
  threads_.clear();
}

// A handler that throws (std::bad_alloc) unwinds out of run(); the io_context stays usable
// and run() is simply called again (Asio's documented pattern). The session whose handler
// threw has lost its pending operation and is freed: that connection closes, nothing else.
void Server::run_io() {
  lower_priority(options_.io_nice);
  while (true) {
    try {
      ioc_.run();
      return;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "tumble-server: I/O handler failed: %s (connection dropped)\n",
                   e.what());
    }
  }
}

std::uint16_t Server::port() const { return listener_ ? listener_->port() : 0; }

std::string Server::url() const {
  const net::ip::address address = net::ip::make_address(options_.bind);
  std::string host = address.is_unspecified() ? std::string("127.0.0.1") : options_.bind;
  if (address.is_v6() && !address.is_unspecified()) host = "[" + host + "]";
  return "http://" + host + ":" + std::to_string(port()) + "/";
}

}  // namespace tumble::server
