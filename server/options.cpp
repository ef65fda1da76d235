#include "options.hpp"

#include <boost/asio/ip/address.hpp>
#include <boost/program_options.hpp>

#include <algorithm>
#include <cctype>
#include <sstream>


namespace po = boost::program_options;

namespace tumble::server {
namespace {

po::options_description describe() {
  po::options_description d("tumble-server options (each also from env TUMBLE_<NAME>, e.g. "
                            "TUMBLE_PORT; the command line wins)");
  d.add_options()
      ("help,h", "print this help and exit")
      ("scene", po::value<std::string>()->default_value("seed"),
       "bundled scene name or path to a scene JSON file")
      ("port", po::value<int>()->default_value(8080), "TCP port (0: any free port)")
      ("bind", po::value<std::string>()->default_value("127.0.0.1"), "address to listen on")
      ("render-ms", po::value<int>()->default_value(20), "WebSocket frame interval, ms (1-1000)")
      ("web-root", po::value<std::string>()->default_value(default_web_root().string()),
       "directory of the viewer's static files")
      ("threads", po::value<int>()->default_value(2), "I/O threads (1-64)")
      ("io-nice", po::value<int>()->default_value(5),
       "nice value of the I/O threads (0-19): on a busy machine they yield to the simulation")
      ("token", po::value<std::string>()->default_value(""),
       "bearer token required on POST requests (empty: none)")
      ("max-viewers", po::value<int>()->default_value(64), "most WebSocket viewers (1-10000)")
      ("allowed-origin", po::value<std::string>()->default_value(""),
       "browser Origin allowed besides the server's own ('*': any)")
      ("token-reads", po::value<bool>()->default_value(false)->implicit_value(true),
       "with --token: also require it on GETs (but /api/health) and on /ws")
      ("max-connections", po::value<int>()->default_value(512),
       "most open connections, HTTP and WebSocket (1-100000); beyond: 503")
      ("sim-threads", po::value<int>()->default_value(0),
       "simulation threads shared by all worlds (0: one per core, 1-256)")
      ("step-threads", po::value<int>()->default_value(1),
       "threads of each world's physics step (1-256); results are the same for any count. "
       "Default 1: the cores also serve other worlds and the viewers (docs/engine.md, Threads)")
      ("max-worlds", po::value<int>()->default_value(64),
       "most worlds on this server, the default counted (1-10000); beyond: 429")
      ("max-bodies", po::value<int>()->default_value(10000),
       "most bodies in a scene sent by a client (PUT /api/worlds, reset; 1-100000)")
      ("idle-s", po::value<double>()->default_value(300),
       "pause a world (not the default) with no viewer and no request for this long, s")
      ("idle-remove-s", po::value<double>()->default_value(3600),
       "remove such a world after this long idle, s (at least --idle-s)")
      ("history-s", po::value<double>()->default_value(60),
       "sim seconds of history (seek, replay) each world keeps (0: none; at most 86400)")
      ("history-mb", po::value<int>()->default_value(64),
       "most MiB of history per world (1-65536): checkpoints are thinned, then dropped, to fit")
      ("step-budget-ms", po::value<int>()->default_value(5000),
       "wall-time budget of one POST /api/step, ms (10-600000)")
      ("viewer-timeout-ms", po::value<int>()->default_value(15000),
       "drop a viewer that answers no ping for this long, ms (1000-600000)")
      ("read-budget", po::value<double>()->default_value(20000),
       "body records per second per client address for /api/state and /api/scene (0: off)");
  return d;
}

std::string usage(const po::options_description& d) {
  std::ostringstream out;
  out << "Usage: tumble-server [options]\n" << d;
  return out.str();
}

std::string env_to_option(const po::options_description& d, const std::string& env) {
  constexpr std::string_view kPrefix = "TUMBLE_";
  if (env.rfind(kPrefix, 0) != 0) return {};
  std::string name = env.substr(kPrefix.size());
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) {
    return c == '_' ? '-' : static_cast<char>(std::tolower(c));
  });
  if (name == "help" || !d.find_nothrow(name, false)) return {};
  return name;
}

ParsedOptions bad(std::string message, const po::options_description& d) {
  return {std::nullopt, 2, "tumble-server: " + message + "\n\n" + usage(d)};
}

}  // namespace

std::filesystem::path default_web_root() { return TUMBLE_SOURCE_WEB_ROOT; }

ParsedOptions parse_options(int argc, const char* const argv[]) {
  const po::options_description d = describe();
  po::variables_map vm;
  try {
    // The first store of a value wins: the command line, then the environment.
    po::store(po::parse_command_line(argc, argv, d), vm);
    po::store(po::parse_environment(
                  d, [&d](const std::string& env) { return env_to_option(d, env); }),
              vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    return bad(e.what(), d);
  }
  if (vm.count("help")) return {std::nullopt, 0, usage(d)};

  ServerOptions o;
  o.scene = vm["scene"].as<std::string>();
  const int port = vm["port"].as<int>();
  if (port < 0 || port > 65535) return bad("--port must be in 0..65535", d);
  o.port = static_cast<std::uint16_t>(port);
  o.bind = vm["bind"].as<std::string>();
  boost::system::error_code ec;
  boost::asio::ip::make_address(o.bind, ec);
  if (ec) return bad("--bind is not an IP address: " + o.bind, d);
  o.render_ms = vm["render-ms"].as<int>();
  if (o.render_ms < 1 || o.render_ms > 1000) return bad("--render-ms must be in 1..1000", d);
  o.web_root = vm["web-root"].as<std::string>();
  o.threads = vm["threads"].as<int>();
  if (o.threads < 1 || o.threads > 64) return bad("--threads must be in 1..64", d);
  o.io_nice = vm["io-nice"].as<int>();
  if (o.io_nice < 0 || o.io_nice > 19) return bad("--io-nice must be in 0..19", d);
  o.token = vm["token"].as<std::string>();
  o.max_viewers = vm["max-viewers"].as<int>();
  if (o.max_viewers < 1 || o.max_viewers > 10000)
    return bad("--max-viewers must be in 1..10000", d);
  o.allowed_origin = vm["allowed-origin"].as<std::string>();
  o.token_reads = vm["token-reads"].as<bool>();
  if (o.token_reads && o.token.empty()) return bad("--token-reads needs --token", d);
  o.max_connections = vm["max-connections"].as<int>();
  if (o.max_connections < 1 || o.max_connections > 100000)
    return bad("--max-connections must be in 1..100000", d);
  o.sim_threads = vm["sim-threads"].as<int>();
  if (o.sim_threads < 0 || o.sim_threads > 256) return bad("--sim-threads must be in 0..256", d);
  o.step_threads = vm["step-threads"].as<int>();
  if (o.step_threads < 1 || o.step_threads > 256)
    return bad("--step-threads must be in 1..256", d);
  o.max_worlds = vm["max-worlds"].as<int>();
  if (o.max_worlds < 1 || o.max_worlds > 10000) return bad("--max-worlds must be in 1..10000", d);
  o.max_bodies = vm["max-bodies"].as<int>();
  if (o.max_bodies < 1 || o.max_bodies > 100000)
    return bad("--max-bodies must be in 1..100000", d);
  o.idle_s = vm["idle-s"].as<double>();
  if (!(o.idle_s >= 0.1 && o.idle_s <= 1e7)) return bad("--idle-s must be in 0.1..1e7", d);
  o.idle_remove_s = vm["idle-remove-s"].as<double>();
  if (!(o.idle_remove_s >= o.idle_s && o.idle_remove_s <= 1e8))
    return bad("--idle-remove-s must be at least --idle-s and at most 1e8", d);
  o.history_s = vm["history-s"].as<double>();
  if (!(o.history_s >= 0.0 && o.history_s <= 86400))
    return bad("--history-s must be in 0..86400", d);
  o.history_mb = vm["history-mb"].as<int>();
  if (o.history_mb < 1 || o.history_mb > 65536) return bad("--history-mb must be in 1..65536", d);
  o.step_budget_ms = vm["step-budget-ms"].as<int>();
  if (o.step_budget_ms < 10 || o.step_budget_ms > 600000)
    return bad("--step-budget-ms must be in 10..600000", d);
  o.viewer_timeout_ms = vm["viewer-timeout-ms"].as<int>();
  if (o.viewer_timeout_ms < 1000 || o.viewer_timeout_ms > 600000)
    return bad("--viewer-timeout-ms must be in 1000..600000", d);
  o.read_budget = vm["read-budget"].as<double>();
  if (!(o.read_budget >= 0.0 && o.read_budget <= 1e9))
    return bad("--read-budget must be in 0..1e9", d);
  if (o.scene.empty()) return bad("--scene must not be empty", d);
  return {o, 0, {}};
}

}  // namespace tumble::server
