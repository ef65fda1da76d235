#pragma once
// The server context the request fuzz targets hand to handle_api: worlds whose default
// world is never started (every command completes at once with 503) and that take no new
// world (--max-worlds 1: a PUT is parsed, then refused with 429), limits, built once per
// fuzzing process. Not thread-safe (libFuzzer calls one input at a time).
#include <chrono>
#include <filesystem>
#include <string>

#include <boost/asio/io_context.hpp>

#include "server.hpp"
#include "tumble/scene_io.hpp"

namespace tumble::server::fuzz {

/// Everything ServerContext points to, with the given POST token and allowed origin ("" off).
struct ServerFixture {
  ServerOptions options = [] {
    ServerOptions o;
    o.max_worlds = 1;
    return o;
  }();
  Metrics metrics;
  SimPool pool{1};
  boost::asio::io_context ioc;
  WorldRegistry worlds{ioc, pool, metrics, options, tumble::load_scene("seed")};
  ConnectionCount connections{64};
  ReadBudget read_budget{0, 0};
  StaticCache static_cache;
  ServerContext ctx{options,     std::filesystem::temp_directory_path(), worlds, metrics,
                    connections, read_budget, static_cache};
  explicit ServerFixture(std::string token = "", std::string allowed_origin = "") {
    options.token = std::move(token);
    options.allowed_origin = std::move(allowed_origin);
    worlds.default_world()->sim().stop();  // never started
  }
};

}  // namespace tumble::server::fuzz
