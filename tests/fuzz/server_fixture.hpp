#pragma once
// The server context the request fuzz targets hand to handle_api: a SimLoop that is never
// started (every command completes at once with 503), its broadcaster and limits, built once
// per fuzzing process. Not thread-safe (libFuzzer calls one input at a time).
#include <chrono>
#include <filesystem>
#include <string>

#include <boost/asio/io_context.hpp>

#include "server.hpp"
#include "tumble/scene_io.hpp"

namespace tumble::server::fuzz {

/// Everything ServerContext points to, with the given POST token and allowed origin ("" off).
struct ServerFixture {
  ServerOptions options;
  Metrics metrics;
  SimLoop sim{tumble::load_scene("seed"), metrics};
  boost::asio::io_context ioc;
  Broadcaster broadcaster{ioc, sim, metrics, std::chrono::milliseconds(20), 4};
  ConnectionCount connections{64};
  ReadBudget read_budget{0, 0};
  StaticCache static_cache;
  ServerContext ctx{options,     std::filesystem::temp_directory_path(), sim, broadcaster, metrics,
                    connections, read_budget, static_cache};
  explicit ServerFixture(std::string token = "", std::string allowed_origin = "") {
    options.token = std::move(token);
    options.allowed_origin = std::move(allowed_origin);
    sim.stop();  // never started
  }
};

}  // namespace tumble::server::fuzz
