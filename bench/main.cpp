/// tumble-bench: every benchmark figure of docs/benchmarks.md from one command.
///   tumble-bench all                 # everything (≈ 25 min, estimated), writes results and docs
///   tumble-bench all --quick         # short version (< 60 s), used by ctest
///   tumble-bench work-precision      # one question only; the docs are re-assembled
///   tumble-bench contact --only pyramid_large   # one scene of contact (or stages)
#include <boost/program_options.hpp>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "tumble/world.hpp"
#include <sys/utsname.h>
#include <thread>

#include "benchmarks.hpp"
#include "report.hpp"

namespace po = boost::program_options;
using namespace tumble_bench;

namespace {

// Box3D is built in only by hand, beside Tumble (bench/README.md): the page says so.
#ifdef TUMBLE_BENCH_HAVE_BOX3D
constexpr bool kWithBox3d = true;
#else
constexpr bool kWithBox3d = false;
#endif

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
  // The whole project is built with one instruction set (CMakeLists.txt, TUMBLE_AVX2); the
  // peers are Debian's packages, built for any x86-64, and Box3D (when built in) its own
  // Release build (SSE2).
#ifdef __AVX2__
  const std::string isa = "Tumble built with AVX2 (no FMA)";
#else
  const std::string isa = "Tumble built for any x86-64";
#endif
  return cpu + ", " + std::to_string(std::thread::hardware_concurrency()) + " logical cores, " +
         u.sysname + " " + u.release + ", compiler " + __VERSION__ + ", " + isa +
         ", the peers as Debian packages them" +
         (kWithBox3d ? " (Box3D as built beside, its Release build)" : "");
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

namespace {

/// The subcommands in the order `all` runs them.
const std::vector<std::pair<std::string, std::function<void(const Options&)>>> kCommands{
    {"work-precision", run_work_precision},
    {"stability", run_stability},
    {"throughput", run_throughput},
    {"skip", run_skip},
    {"peers", run_peers},
    {"contact", run_contact},
    {"pile-precision", run_pile_precision},
    {"stages", run_stages},
};

bool known(const std::string& command) {
  if (command == "all") return true;
  for (const auto& [name, run] : kCommands)
    if (name == command) return true;
  return false;
}

/// "a,b" → {"a", "b"} (empty items dropped).
std::vector<std::string> split_commas(const std::string& list) {
  std::vector<std::string> items;
  std::istringstream in(list);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) items.push_back(item);
  return items;
}

/// What the command line asked for.
struct Invocation {
  Options o;
  std::string command;
  std::string only;            // as typed, for the page's command line
  bool default_paths = false;  // --out and --docs left at their defaults
};

/// Parses argv; returns an exit code when the program should stop (help, bad usage).
std::optional<int> parse(int argc, char** argv, Invocation& inv) {
  std::string out, docs;
  const std::string src = TUMBLE_BENCH_SOURCE_DIR;
  po::options_description visible(
      "Usage: tumble-bench <all|work-precision|stability|throughput|skip|peers|contact|pile-precision|stages> "
      "[options]\nOptions");
  visible.add_options()("help,h", "this help")(
      "quick", po::bool_switch(&inv.o.quick), "short version of everything (< 60 s), for ctest")(
      "out", po::value(&out)->default_value(src + "/bench/results"),
      "results directory (CSV, SVG plots, section markdown)")(
      "docs", po::value(&docs)->default_value(src + "/docs/benchmarks.md"),
      "Markdown page assembled from the results")("no-plots", "skip gnuplot")(
      "repeats", po::value(&inv.o.repeats)->default_value(3),
      "interleaved repetitions of each timing (median)")(
      "threads", po::value(&inv.o.threads)->default_value(tumble::World::hardware_threads()),
      "contact: also time Tumble on this many threads (default: one per core; 1: only one)")(
      "only", po::value(&inv.only),
      "contact, stages: only these scenes, comma-separated (e.g. pyramid_large)");
  po::options_description all;
  all.add(visible).add_options()("command", po::value(&inv.command));
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
  if (vm.count("help") || !known(inv.command)) {
    std::cerr << visible << '\n';
    return vm.count("help") ? 0 : 2;
  }
  inv.o.out = out;
  inv.o.docs = docs;
  inv.o.plots = !vm.count("no-plots");
  if (inv.o.quick) inv.o.repeats = std::min(inv.o.repeats, 1);
  inv.o.only = split_commas(inv.only);
  if (inv.o.threads < 1 || inv.o.threads > 256) {
    std::cerr << "--threads must be within [1, 256]\n" << visible << '\n';
    return 2;
  }
  inv.default_paths = vm["out"].defaulted() && vm["docs"].defaulted();
  return std::nullopt;
}

/// The command printed at the top of the page: the whole build-and-run recipe when the
/// results go to their default places, else the bench command alone.
std::string page_command_line(const Invocation& inv) {
  const std::string bench = "tumble-bench " + inv.command + (inv.o.quick ? " --quick" : "") +
                            (inv.only.empty() ? "" : " --only " + inv.only);
  if (!inv.default_paths) return bench;
  const std::string box3d = kWithBox3d ? " -DTUMBLE_BOX3D_ROOT=../box3d" : "";
  return "cmake -S . -B build/bench -G Ninja -DCMAKE_BUILD_TYPE=Release "
         "-DCMAKE_CXX_COMPILER=clang++ -DTUMBLE_BUILD_SERVER=OFF" +
         box3d + " && ninja -C build/bench tumble-bench && build/bench/bench/" + bench;
}

}  // namespace

int main(int argc, char** argv) {
  Invocation inv;
  if (const std::optional<int> stop = parse(argc, argv, inv)) return *stop;
  const Options& o = inv.o;
  fs::create_directories(o.out);
  record_value(o, "machine", machine_description());
  record_value(o, "date", today());
  record_value(o, "engine_commit", engine_commit());

  const double start = wall_seconds();
  int failures = 0;
  for (const auto& [name, run] : kCommands) {
    if (inv.command != "all" && inv.command != name) continue;
    std::cerr << "== " << name << '\n';
    try {
      run(o);
    } catch (const std::exception& e) {
      std::cerr << name << " failed: " << e.what() << '\n';
      ++failures;
    }
    assemble_docs(o, page_command_line(inv));
  }
  std::cerr << "done in " << fixed(wall_seconds() - start, 1) << " s; docs: " << o.docs.string()
            << '\n';
  return failures == 0 ? 0 : 1;
}
