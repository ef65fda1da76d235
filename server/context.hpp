#pragma once
/// What HTTP and WebSocket sessions share: configuration and the long-lived parts of the
/// server. Every member outlives every session; each is thread-safe.
#include <filesystem>

#include "admission.hpp"
#include "broadcaster.hpp"
#include "metrics.hpp"
#include "options.hpp"
#include "sim_loop.hpp"
#include "static_cache.hpp"

namespace tumble::server {

/// References to the server's parts, handed to each session.
struct ServerContext {
  const ServerOptions& options;      ///< As parsed.
  std::filesystem::path web_root;    ///< Canonical absolute web root.
  SimLoop& sim;                      ///< Commands go here; snapshots come from here.
  Broadcaster& broadcaster;          ///< Viewers join here.
  Metrics& metrics;                  ///< Counters.
  ConnectionCount& connections;      ///< Open connections against --max-connections.
  ReadBudget& read_budget;           ///< Per-client budget of /api/state and /api/scene.
  StaticCache& static_cache;         ///< ETags and gzip copies of static files.
  int web_root_fd = -1;              ///< The web root opened O_PATH (static files open beneath it).
};

}  // namespace tumble::server
