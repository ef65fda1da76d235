#pragma once
/// What HTTP and WebSocket sessions share: configuration and the long-lived parts of the
/// server. Every member outlives every session; each is thread-safe.
#include <filesystem>

#include "admission.hpp"
#include "metrics.hpp"
#include "options.hpp"
#include "static_cache.hpp"
#include "worlds.hpp"

namespace tumble::server {

/// References to the server's parts, handed to each session.
struct ServerContext {
  const ServerOptions& options;      ///< As parsed.
  std::filesystem::path web_root;    ///< Canonical absolute web root.
  WorldRegistry& worlds;             ///< The worlds: commands, snapshots, viewers.
  Metrics& metrics;                  ///< Counters.
  ConnectionCount& connections;      ///< Open connections against --max-connections.
  ReadBudget& read_budget;           ///< Per-client budget of /api/state and /api/scene.
  StaticCache& static_cache;         ///< ETags and gzip copies of static files.
  int web_root_fd = -1;              ///< The web root opened O_PATH (static files open beneath it).
};

}  // namespace tumble::server
