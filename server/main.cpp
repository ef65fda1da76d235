/// tumble-server: serves the viewer, the REST API and the WebSocket stream of one simulation.
/// Exit codes: 0 after SIGINT/SIGTERM/SIGHUP (or --help), 1 when it cannot listen, 2 for bad
/// input. SIGPIPE is ignored: a closed stdout/stderr pipe makes a write fail, not the process.
#include <csignal>
#include <cstdio>
#include <iostream>

#include <boost/system/system_error.hpp>

#include "options.hpp"
#include "server.hpp"
#include "tumble/scene_io.hpp"

int main(int argc, char* argv[]) {
  using namespace tumble::server;
  std::signal(SIGPIPE, SIG_IGN);  // First, before anything can write to a closed pipe.
  const ParsedOptions parsed = parse_options(argc, argv);
  if (!parsed.options) {
    (parsed.exit_code == 0 ? std::cout : std::cerr) << parsed.message << std::flush;
    return parsed.exit_code;
  }
  const ServerOptions& options = *parsed.options;

  tumble::Scene scene;
  try {
    scene = tumble::load_scene(options.scene);
  } catch (const tumble::SceneParseError& e) {
    std::cerr << "tumble-server: cannot load scene '" << options.scene << "'"
              << (e.field.empty() ? "" : " (field " + e.field + ")") << ": " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "tumble-server: cannot load scene '" << options.scene << "': " << e.what()
              << '\n';
    return 2;
  }

  // Signals are taken synchronously by this thread alone: block them before any thread starts.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGHUP);  // The terminal went away: the same graceful stop.
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  try {
    Server server(options, std::move(scene));
    try {
      server.start();
    } catch (const boost::system::system_error& e) {
      std::cerr << "tumble-server: cannot listen on " << options.bind << ':' << options.port
                << ": " << e.code().message() << '\n';
      return 1;
    }
    std::cout << "Tumble viewer: " << server.url() << std::endl;
    int signal = 0;
    sigwait(&signals, &signal);
    server.stop();
  } catch (const std::exception& e) {
    std::cerr << "tumble-server: " << e.what() << '\n';
    return 1;
  }
  return 0;
}
