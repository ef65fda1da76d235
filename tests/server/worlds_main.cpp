/// server_worlds: how many worlds of one scene a tumble-server keeps at real time on this
/// machine (docs/benchmarks.md, "Worlds per server"), against a child server on 127.0.0.1:
///   server_worlds [--server PATH] [--scene seed] [--max N] [--seconds S] [--settle S]
///                 [--sim-threads T]
/// For a count n it creates n worlds (PUT /api/worlds/w-i, the default world paused so it
/// costs nothing), waits 2.5 s (the real-time factor is a 2 s window), then samples
/// GET /api/worlds every 0.5 s for S seconds (default 4): n passes when every world's factor
/// stays ≥ 0.99 in every sample. It doubles n from 1 while n passes, then bisects between the
/// last pass and the first failure, each count on a fresh server. Prints per count the
/// worst and mean factor, the server's CPU use while sampled, its memory per world and the
/// share of bodies awake at the end (a scene that falls asleep costs little once it has:
/// `--settle S` waits longer before sampling, to measure that state); last line: the largest
/// count that passed.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>

#include "child_process.hpp"
#include "test_client.hpp"

using namespace tumble::server::test;
namespace http = boost::beast::http;
using Clock = std::chrono::steady_clock;

namespace {

struct Args {
  std::string server = TUMBLE_SERVER_BINARY;
  std::string scene = "seed";
  int max = 4096;
  double seconds = 4.0;
  int sim_threads = 0;
  double settle = 2.5;
};

struct Trial {
  int worlds = 0;
  bool pass = false;
  double worst = 0, mean = 0;   // Real-time factor over worlds and samples.
  double cpu = 0;               // Server CPU seconds per wall second while sampled.
  double rss_per_world_kb = 0;  // Resident memory growth per world created, KiB.
  double awake = 0;             // Share of bodies awake at the end (asleep bodies cost less).
  std::string why;
};

// utime + stime of `pid`, s, and its resident set, KiB.
std::pair<double, double> usage(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), {});
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::string skip;
  for (int i = 0; i < 11; ++i) fields >> skip;  // state … cmajflt
  double utime = 0, stime = 0;
  fields >> utime >> stime;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  double rss = 0;
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) rss = std::stod(line.substr(6));
  return {(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK)), rss};
}

Trial run(const Args& a, int n) {
  Trial t;
  t.worlds = n;
  std::vector<std::string> argv = {a.server,
                                   "--port",
                                   "0",
                                   "--max-worlds",
                                   std::to_string(n + 1),
                                   "--sim-threads",
                                   std::to_string(a.sim_threads)};
  ChildProcess child(argv);
  const std::string url = child.line();
  if (url.find("http://") == std::string::npos) return t.why = "no server: " + url, t;
  const auto port = static_cast<std::uint16_t>(std::stoi(url.substr(url.rfind(':') + 1)));
  http_post(port, "/api/pause");
  const double rss0 = usage(child.pid()).second;
  for (int i = 0; i < n; ++i) {
    const HttpReply r = http_request(port, http::verb::put, "/api/worlds/w-" + std::to_string(i),
                                     R"({"scene": ")" + a.scene + "\"}");
    if (r.status != 201)
      return t.why = "PUT answered " + std::to_string(r.status) + " " + r.body, t;
  }
  t.rss_per_world_kb = (usage(child.pid()).second - rss0) / n;
  std::this_thread::sleep_for(std::chrono::duration<double>(a.settle));
  const auto [cpu0, rss1] = usage(child.pid());
  const auto start = Clock::now();
  t.worst = 1e9;
  double sum = 0;
  int count = 0;
  while (Clock::now() - start < std::chrono::duration<double>(a.seconds)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    const nlohmann::json list = http_get(port, "/api/worlds").json();
    for (const auto& w : list["worlds"]) {
      if (w["id"] == "default") continue;
      const double f = w["real_time_factor"];
      t.worst = std::min(t.worst, f);
      sum += f;
      ++count;
    }
  }
  t.cpu = (usage(child.pid()).first - cpu0) /
          std::chrono::duration<double>(Clock::now() - start).count();
  t.mean = count ? sum / count : 0;
  double awake = 0, bodies = 0;
  std::istringstream metrics(http_get(port, "/metrics").body);
  for (std::string line; std::getline(metrics, line);) {
    if (line.rfind("tumble_world_bodies_awake{", 0) == 0 &&
        line.find("\"default\"") == std::string::npos)
      awake += std::stod(line.substr(line.rfind(' ') + 1));
    if (line.rfind("tumble_world_bodies{", 0) == 0 && line.find("\"default\"") == std::string::npos)
      bodies += std::stod(line.substr(line.rfind(' ') + 1));
  }
  t.awake = bodies > 0 ? awake / bodies : 0;
  t.pass = count > 0 && t.worst >= 0.99;
  child.stop();
  return t;
}

void print(const Trial& t) {
  std::printf(
      "%6d worlds: real-time factor worst %.3f mean %.3f, server CPU %.2f cores, "
      "%.0f KiB per world, %.0f %% of bodies awake at the end  %s%s\n",
      t.worlds, t.worst, t.mean, t.cpu, t.rss_per_world_kb, 100 * t.awake, t.pass ? "pass" : "FAIL",
      t.why.empty() ? "" : ("  (" + t.why + ")").c_str());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--server")
      a.server = v;
    else if (k == "--scene")
      a.scene = v;
    else if (k == "--max")
      a.max = std::stoi(v);
    else if (k == "--seconds")
      a.seconds = std::stod(v);
    else if (k == "--settle")
      a.settle = std::stod(v);
    else if (k == "--sim-threads")
      a.sim_threads = std::stoi(v);
    else
      return std::cerr << "server_worlds: unknown option " << k << "\n", 2;
  }
  std::signal(SIGPIPE, SIG_IGN);
  std::printf("scene %s, %u cores, --sim-threads %d (0: the cores)\n", a.scene.c_str(),
              std::thread::hardware_concurrency(), a.sim_threads);
  int pass = 0, fail = 0;
  for (int n = 1; n <= a.max; n *= 2) {
    const Trial t = run(a, n);
    print(t);
    if (!t.pass) {
      fail = n;
      break;
    }
    pass = n;
  }
  while (fail && fail - pass > std::max(1, pass / 16)) {
    const int mid = (pass + fail) / 2;
    const Trial t = run(a, mid);
    print(t);
    (t.pass ? pass : fail) = mid;
  }
  std::printf("largest count at real-time factor >= 0.99: %d worlds of %s%s\n", pass,
              a.scene.c_str(), fail ? "" : " (the --max tried; more may pass)");
  return 0;
}
