#pragma once
/// Command-line and environment configuration of tumble-server.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace tumble::server {

/// Everything the server is configured with. Plain data.
struct ServerOptions {
  std::string scene = "seed";          ///< Bundled scene name or a path to a scene file.
  std::uint16_t port = 8080;           ///< TCP port; 0 picks a free one.
  std::string bind = "127.0.0.1";      ///< Address to listen on.
  int render_ms = 20;                  ///< Interval between WebSocket frames, ms.
  std::filesystem::path web_root;      ///< Directory of the viewer's static files.
  int threads = 2;                     ///< I/O threads (the simulation has its own).
  int io_nice = 5;                     ///< Nice value of the I/O threads (0..19; 0: as the rest).
  int sim_threads = 0;                 ///< Simulation threads all worlds share (0: the cores).
  int step_threads = 1;                ///< Threads of each physics step (World::set_threads).
  std::string token;                   ///< Bearer token for POSTs; empty: none required.
  int max_viewers = 64;                ///< Most WebSocket viewers at once.
  std::string allowed_origin;          ///< Origin allowed besides the server's own; "*": any.
  bool token_reads = false;            ///< --token also on GETs (but /api/health) and /ws.
  int max_connections = 512;           ///< Most open connections (HTTP + WebSocket) at once.
  int step_budget_ms = 5000;           ///< Wall-time budget of one POST /api/step, ms.
  int viewer_timeout_ms = 15000;       ///< A viewer that answers no ping this long is dropped, ms.
  double read_budget = 20000;          ///< Body records/s per client for /api/state, /api/scene.
  int max_worlds = 64;                 ///< Most worlds, the default counted (PUT beyond: 429).
  int max_bodies = 10000;              ///< Most bodies in a scene sent over REST (beyond: 400).
  double idle_s = 300;                 ///< A world with no viewer or request this long pauses, s.
  double idle_remove_s = 3600;         ///< … and is removed after this long, s.
  double history_s = 60;               ///< Sim seconds of timeline kept per world (0: none).
  int history_mb = 64;                 ///< Most MiB of timeline per world (checkpoints, log).
};

/// Result of parsing: options, or an exit code with the text to print.
struct ParsedOptions {
  std::optional<ServerOptions> options;  ///< Set when the server should start.
  int exit_code = 0;                     ///< 0 after --help, 2 for bad input.
  std::string message;                   ///< Usage or error text.
};

/// The source tree's web/ directory (the default --web-root).
std::filesystem::path default_web_root();

/// Parses argv, then the TUMBLE_* environment (TUMBLE_PORT → --port …); the command line wins.
/// Never throws.
ParsedOptions parse_options(int argc, const char* const argv[]);

}  // namespace tumble::server
