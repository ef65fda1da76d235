#pragma once
/// What HTTP and WebSocket sessions share: configuration and the long-lived parts of the
/// server. Every member outlives every session; each is thread-safe.
#include <filesystem>

#include "broadcaster.hpp"
#include "metrics.hpp"
#include "options.hpp"
#include "sim_loop.hpp"

namespace tumble::server {

/// References to the server's parts, handed to each session.
struct ServerContext {
  const ServerOptions& options;      ///< As parsed.
  std::filesystem::path web_root;    ///< Canonical absolute web root.
  SimLoop& sim;                      ///< Commands go here; snapshots come from here.
  Broadcaster& broadcaster;          ///< Viewers join here.
  Metrics& metrics;                  ///< Counters.
};

}  // namespace tumble::server
