/// tumble-bench: every benchmark figure of docs/benchmarks.md from one command.
///   tumble-bench all                 # everything (≈ 15 min), writes bench/results and docs
///   tumble-bench all --quick         # short version (< 60 s), used by ctest
///   tumble-bench work-precision      # one question only; the docs are re-assembled
#include <boost/program_options.hpp>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <sys/utsname.h>
#include <thread>

#include "benchmarks.hpp"
#include "report.hpp"

namespace po = boost::program_options;
using namespace tumble_bench;

namespace {

std::string machine_description() {
  std::string cpu = "unknown CPU";
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  }
  utsname u{};
  uname(&u);
  return cpu + ", " + std::to_string(std::thread::hardware_concurrency()) + " logical cores, " +
         u.sysname + " " + u.release + ", compiler " + __VERSION__;
}

/// The engine commit measured: $TUMBLE_BENCH_COMMIT if set (a build from an exported tree),
/// else `git rev-parse --short HEAD` of the source tree, marked "+ local changes" when
/// engine/ differs from it.
std::string engine_commit() {
  if (const char* env = std::getenv("TUMBLE_BENCH_COMMIT")) return env;
  const std::string src = TUMBLE_BENCH_SOURCE_DIR;
  auto run = [](const std::string& cmd) {
    std::string out;
    if (FILE* p = ::popen(cmd.c_str(), "r")) {
      char buf[256];
      while (std::fgets(buf, sizeof buf, p)) out += buf;
      ::pclose(p);
    }
    while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
    return out;
  };
  const std::string head = run("git -C '" + src + "' rev-parse --short HEAD 2>/dev/null");
  if (head.empty()) return "unknown";
  const std::string dirty =
      run("git -C '" + src + "' status --porcelain -- engine reference 2>/dev/null");
  return head + (dirty.empty() ? "" : " + local changes");
}

std::string today() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d", std::gmtime(&t));
  return buf;
}

}  // namespace

int main(int argc, char** argv) {
  const std::map<std::string, std::function<void(const Options&)>> commands{
      {"work-precision", run_work_precision},
      {"stability", run_stability},
      {"throughput", run_throughput},
      {"skip", run_skip},
      {"peers", run_peers},
      {"contact", run_contact},
      {"stages", run_stages},
  };
  Options o;
  std::string command, out, docs, only;
  po::options_description visible(
      "Usage: tumble-bench <all|work-precision|stability|throughput|skip|peers|contact|stages> "
      "[options]\n"
      "Options");
  visible.add_options()("help,h", "this help")(
      "quick", po::bool_switch(&o.quick), "short version of everything (< 60 s), for ctest")(
      "out", po::value(&out)->default_value(std::string(TUMBLE_BENCH_SOURCE_DIR) + "/bench/results"),
      "results directory (CSV, SVG plots, section markdown)")(
      "docs", po::value(&docs)->default_value(std::string(TUMBLE_BENCH_SOURCE_DIR) + "/docs/benchmarks.md"),
      "Markdown page assembled from the results")(
      "no-plots", "skip gnuplot")("repeats", po::value(&o.repeats)->default_value(3),
                                 "interleaved repetitions of each timing (median)")(
      "only", po::value(&only),
      "contact, stages: only these scenes, comma-separated (e.g. pyramid_large)");
  po::options_description hidden;
  hidden.add_options()("command", po::value(&command));
  po::options_description all;
  all.add(visible).add(hidden);
  po::positional_options_description pos;
  pos.add("command", 1);
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(argc, argv).options(all).positional(pos).run(), vm);
    po::notify(vm);
  } catch (const std::exception& e) {
    std::cerr << e.what() << '\n' << visible << '\n';
    return 2;
  }
  if (vm.count("help") || command.empty() || (command != "all" && !commands.count(command))) {
    std::cerr << visible << '\n';
    return vm.count("help") ? 0 : 2;
  }
  o.out = out;
  o.docs = docs;
  o.plots = !vm.count("no-plots");
  if (o.quick) o.repeats = std::min(o.repeats, 1);
  for (std::size_t a = 0; !only.empty() && a <= only.size();) {
    const std::size_t b = std::min(only.find(',', a), only.size());
    if (b > a) o.only.push_back(only.substr(a, b - a));
    a = b + 1;
  }
  fs::create_directories(o.out);

  std::ostringstream cmdline;
  cmdline << "tumble-bench " << command << (o.quick ? " --quick" : "")
          << (only.empty() ? "" : " --only " + only);
  if (vm["out"].defaulted() && vm["docs"].defaulted()) {
    cmdline.str("");
    cmdline << "cmake -S . -B build/bench -G Ninja -DCMAKE_BUILD_TYPE=Release "
               "-DTUMBLE_BUILD_SERVER=OFF && ninja -C build/bench tumble-bench && "
               "build/bench/bench/tumble-bench "
            << command << (o.quick ? " --quick" : "");
  }
  record_value(o, "machine", machine_description());
  record_value(o, "date", today());
  record_value(o, "engine_commit", engine_commit());

  const double start = wall_seconds();
  const std::vector<std::string> order = {"work-precision", "stability", "throughput", "skip",
                                          "peers", "contact", "stages"};
  int failures = 0;
  for (const std::string& name : order) {
    if (command != "all" && command != name) continue;
    std::cerr << "== " << name << '\n';
    try {
      commands.at(name)(o);
    } catch (const std::exception& e) {
      std::cerr << name << " failed: " << e.what() << '\n';
      ++failures;
    }
    assemble_docs(o, cmdline.str());
  }
  std::cerr << "done in " << fixed(wall_seconds() - start, 1) << " s; docs: " << o.docs.string()
            << '\n';
  return failures == 0 ? 0 : 1;
}
