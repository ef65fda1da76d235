// tumble-sim: runs a scene headless and prints a one-line JSON summary; optionally a CSV of
// every body's state every N steps. `tumble-sim --replay FILE` replays a recording made by the
// server (GET /api/recording) and says whether it ends in the same state: exit 0 match,
// 1 mismatch, 2 unusable file (the message names the field).
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>

#include "recording.hpp"
#include "tumble/scene_io.hpp"
#include "tumble/world.hpp"

namespace po = boost::program_options;

namespace {

constexpr int kUsageError = 2;

struct Options {
  std::string scene;
  double duration = 10.0;
  std::optional<double> dt;
  std::optional<std::string> integrator;
  std::optional<std::string> toi;
  long every = 1;
  std::optional<std::string> csv;
  unsigned threads = tumble::World::hardware_threads();
  std::optional<std::string> replay;
};

int usage_error(const std::string& message, const po::options_description& desc) {
  std::cerr << "tumble-sim: " << message << "\n\nusage: tumble-sim SCENE [options]\n" << desc;
  return kUsageError;
}

// Replays a recording file: exit 0 when the final state's digest matches the file's, 1 when
// not, 2 when the file cannot be used.
int replay_file(const std::string& path, unsigned threads) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::cerr << "tumble-sim: --replay: cannot read " << path << "\n";
    return kUsageError;
  }
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    std::cerr << "tumble-sim: " << path << ": not JSON: " << e.what() << "\n";
    return kUsageError;
  }
  tumble::server::Recording recording;
  tumble::server::ReplayResult result;
  try {
    recording = tumble::server::parse_recording(document);
    result = tumble::server::replay(recording, threads);
  } catch (const tumble::server::RecordingError& e) {
    std::cerr << "tumble-sim: " << path << ": field '" << e.field << "': " << e.what() << "\n";
    return kUsageError;
  }
  const bool match = result.digest == recording.digest && result.step == recording.final_step;
  nlohmann::json summary{{"replay", path},
                         {"scene", recording.scene.world.name},
                         {"commands", recording.commands.size()},
                         {"final_step", result.step},
                         {"final_time", result.time},
                         {"digest", tumble::server::digest_hex(result.digest)},
                         {"expected_digest", tumble::server::digest_hex(recording.digest)},
                         {"match", match}};
  std::cout << summary.dump() << std::endl;
  return match ? 0 : 1;
}

void write_rows(std::ostream& out, const tumble::World& world) {
  const auto& defs = world.scene().bodies;
  const tumble::Vec3 g = world.settings().gravity;
  for (std::size_t i = 0; i < world.bodies().size(); ++i) {
    const tumble::Body& b = world.bodies()[i];
    const tumble::Quat q(b.s.R);
    const tumble::Vec3 v = tumble::velocity(b.s, b.c);
    const tumble::Vec3 w = tumble::angular_velocity(b.s, b.c);
    out << world.time() << ',' << defs[i].name << ',' << b.s.x.x() << ',' << b.s.x.y() << ','
        << b.s.x.z() << ',' << q.w() << ',' << q.x() << ',' << q.y() << ',' << q.z() << ','
        << v.x() << ',' << v.y() << ',' << v.z() << ',' << w.x() << ',' << w.y() << ','
        << w.z() << ',' << tumble::total_energy(b.s, b.c, g) << '\n';
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  po::options_description desc("options");
  desc.add_options()
      ("help,h", "show this help")
      ("duration", po::value(&o.duration), "simulated seconds (default 10)")
      ("dt", po::value<double>(), "physics step in seconds (default: the scene's)")
      ("integrator", po::value<std::string>(), "euler|midpoint|rk4|symplectic_euler|splitting|exact")
      ("toi", po::value<std::string>(), "bisection|root")
      ("max-overlap", po::value<double>(), "deepest a step may sink boxes into each other, m "
                                           "(0: off, else at least 0.001; default: the scene's)")
      ("every", po::value(&o.every), "CSV row every N steps (default 1)")
      ("threads", po::value(&o.threads), "threads per step (default: one per core); any count gives the same result")
      ("csv", po::value<std::string>(), "write body states to this CSV file")
      ("replay", po::value<std::string>(), "replay this recording (GET /api/recording) and compare "
                                           "its final state: exit 0 match, 1 mismatch, 2 bad file");
  po::options_description hidden;
  hidden.add_options()("scene", po::value(&o.scene));
  po::options_description all;
  all.add(desc).add(hidden);
  po::positional_options_description pos;
  pos.add("scene", 1);
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(pos).run(), vm);
    po::notify(vm);
  } catch (const po::error& e) {
    return usage_error(e.what(), desc);
  }
  if (vm.count("help")) {
    std::cout << "usage: tumble-sim SCENE [options] | tumble-sim --replay FILE\nSCENE: a bundled name ("
              << nlohmann::json(tumble::bundled_scene_names()).dump() << ") or a path\n" << desc;
    return 0;
  }
  if (o.threads < 1 || o.threads > 256) return usage_error("--threads must be within [1, 256]", desc);
  if (vm.count("replay")) {
    if (!o.scene.empty()) return usage_error("--replay takes no SCENE", desc);
    return replay_file(vm["replay"].as<std::string>(), o.threads);
  }
  if (o.scene.empty()) return usage_error("missing SCENE", desc);
  if (!(std::isfinite(o.duration) && o.duration >= 0.0 && o.duration <= 1e7))
    return usage_error("--duration must be within [0, 1e7] s", desc);
  if (o.every < 1) return usage_error("--every must be >= 1", desc);
  if (o.threads < 1 || o.threads > 256) return usage_error("--threads must be within [1, 256]", desc);

  tumble::Scene scene;
  try {
    scene = tumble::load_scene(o.scene);
  } catch (const tumble::SceneParseError& e) {
    return usage_error(e.what(), desc);
  }
  if (vm.count("dt")) scene.world.dt = vm["dt"].as<double>();
  if (vm.count("integrator")) {
    const auto i = tumble::parse_integrator(vm["integrator"].as<std::string>());
    if (!i) return usage_error("--integrator: unknown \"" + vm["integrator"].as<std::string>() + "\"", desc);
    scene.world.integrator = *i;
  }
  if (vm.count("toi")) {
    const auto m = tumble::parse_toi_method(vm["toi"].as<std::string>());
    if (!m) return usage_error("--toi: unknown \"" + vm["toi"].as<std::string>() + "\"", desc);
    scene.world.toi = *m;
  }
  if (vm.count("max-overlap")) scene.world.max_overlap = vm["max-overlap"].as<double>();
  if (auto error = tumble::validate(scene)) return usage_error(error->field + ": " + error->message, desc);

  std::ofstream csv;
  if (vm.count("csv")) {
    csv.open(vm["csv"].as<std::string>());
    if (!csv) return usage_error("--csv: cannot write " + vm["csv"].as<std::string>(), desc);
    csv.precision(17);
    csv << "t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz,energy\n";
  }

  tumble::World world(scene);
  world.set_threads(o.threads);
  const long steps = std::lround(o.duration / scene.world.dt);
  if (csv.is_open()) write_rows(csv, world);
  std::uint64_t body_steps = 0, passes = 0, steps_alone = 0;
  const auto start = std::chrono::steady_clock::now();
  for (long k = 1; k <= steps; ++k) {
    world.step();
    body_steps += world.bodies().size();
    passes += world.last_step().passes;
    steps_alone += world.last_step().solo;
    if (csv.is_open() && (k % o.every == 0 || k == steps)) write_rows(csv, world);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  nlohmann::json summary{
      {"scene", scene.world.name},
      {"integrator", std::string(tumble::to_string(scene.world.integrator))},
      {"toi", std::string(tumble::to_string(scene.world.toi))},
      {"steps", steps},
      {"max_overlap", scene.world.max_overlap},
      {"passes", passes},
      {"threads", world.threads()},
      {"steps_alone", steps_alone},
      {"bodies", world.bodies().size()},
      {"impacts", world.total_impacts()},
      {"awake", world.awake_count()},
      {"frozen", world.frozen_count()},
      {"sim_seconds", world.time()},
      {"wall_seconds", wall},
      {"ns_per_body_step", body_steps ? wall * 1e9 / static_cast<double>(body_steps) : 0.0},
      {"final_energy", world.total_energy()}};
  std::cout << summary.dump() << std::endl;
  return 0;
}
