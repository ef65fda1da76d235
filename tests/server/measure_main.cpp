/// server_measure: measures a running tumble-server for the closing note (not a test).
///   server_measure --port P --pid PID [--cadence-s 30] [--rtf-s 10] [--paused-s 10]
/// Prints: real-time factor over --rtf-s; frame cadence at a WebSocket client over
/// --cadence-s (mean, p50, p99, max interval); CPU used by PID while paused over --paused-s,
/// with no viewer and with one viewer connected.
#include <algorithm>
#include <atomic>
#include <memory>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

#include "frame.hpp"
#include "test_client.hpp"

using namespace tumble::server;
using namespace tumble::server::test;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// utime + stime of a process, seconds (/proc/<pid>/stat fields 14 and 15).
double cpu_seconds(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(in, line);
  std::istringstream fields(line.substr(line.rfind(')') + 2));
  std::string f;
  std::vector<std::string> v;
  while (fields >> f) v.push_back(f);
  // After "pid (comm) ", field 3 is v[0]; utime is field 14 → v[11], stime → v[12].
  return (std::stod(v.at(11)) + std::stod(v.at(12))) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

void measure_rtf(std::uint16_t port, double duration) {
  const auto t0 = Clock::now();
  const auto s0 = http_get(port, "/api/state").json();
  std::this_thread::sleep_for(std::chrono::duration<double>(duration));
  const auto s1 = http_get(port, "/api/state").json();
  const double wall = seconds_since(t0);
  const double sim = s1["time"].get<double>() - s0["time"].get<double>();
  std::printf("rtf: sim %.4f s over wall %.4f s = %.4f; reported real_time_factor %.4f\n", sim,
              wall, sim / wall, s1["real_time_factor"].get<double>());
}

void measure_cadence(std::uint16_t port, double duration) {
  WsClient c(port);
  std::vector<double> intervals;
  Clock::time_point last{};
  double last_time = -1;
  int repeats = 0, frames = 0;
  const auto t0 = Clock::now();
  while (seconds_since(t0) < duration) {
    const auto m = c.read(std::chrono::seconds(2));
    if (!m) {
      std::printf("cadence: read failed: %s\n", c.last_error().message().c_str());
      return;
    }
    if (m->text) continue;
    const auto f = decode_frame(m->data);
    if (!f) continue;
    if (frames > 0) {
      intervals.push_back(std::chrono::duration<double, std::milli>(m->at - last).count());
      if (f->time <= last_time) ++repeats;
    }
    last = m->at;
    last_time = f->time;
    ++frames;
  }
  std::vector<double> sorted = intervals;
  std::sort(sorted.begin(), sorted.end());
  double sum = 0;
  for (double x : intervals) sum += x;
  const auto pct = [&](double p) { return sorted[static_cast<std::size_t>(p * (sorted.size() - 1))]; };
  std::printf("cadence: %d frames in %.1f s (%.2f /s); interval mean %.3f ms, p50 %.3f ms, "
              "p99 %.3f ms, max %.3f ms, min %.3f ms; frames not advancing sim time: %d\n",
              frames, duration, frames / duration, sum / intervals.size(), pct(0.5), pct(0.99),
              sorted.back(), sorted.front(), repeats);
}

void measure_paused_cpu(std::uint16_t port, int pid, double duration, bool with_viewer) {
  http_post(port, "/api/pause");
  std::unique_ptr<WsClient> viewer;
  std::thread reader;
  std::atomic<bool> stop{false};
  if (with_viewer) {
    viewer = std::make_unique<WsClient>(port);
    reader = std::thread([&] {
      while (!stop && viewer->read(std::chrono::seconds(2))) {
      }
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const double c0 = cpu_seconds(pid);
  const auto t0 = Clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(duration));
  const double used = cpu_seconds(pid) - c0;
  const double wall = seconds_since(t0);
  stop = true;
  if (reader.joinable()) reader.join();
  http_post(port, "/api/resume");
  std::printf("paused cpu (%s): %.3f s CPU over %.2f s wall = %.2f%% of one core\n",
              with_viewer ? "one viewer" : "no viewer", used, wall, 100.0 * used / wall);
}

}  // namespace

int main(int argc, char* argv[]) {
  std::uint16_t port = 8080;
  int pid = 0;
  double cadence_s = 30, rtf_s = 10, paused_s = 10;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    const std::string v = argv[i + 1];
    if (k == "--port") port = static_cast<std::uint16_t>(std::stoi(v));
    else if (k == "--pid") pid = std::stoi(v);
    else if (k == "--cadence-s") cadence_s = std::stod(v);
    else if (k == "--rtf-s") rtf_s = std::stod(v);
    else if (k == "--paused-s") paused_s = std::stod(v);
  }
  if (pid <= 0) {
    std::cerr << "usage: server_measure --port P --pid PID [--cadence-s 30] [--rtf-s 10] "
                 "[--paused-s 10]\n";
    return 2;
  }
  measure_rtf(port, rtf_s);
  measure_cadence(port, cadence_s);
  measure_paused_cpu(port, pid, paused_s, false);
  measure_paused_cpu(port, pid, paused_s, true);
  std::printf("metrics:\n");
  const std::string metrics = http_get(port, "/metrics").body;
  std::istringstream lines(metrics);
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("tumble_frames", 0) == 0 || line.rfind("tumble_dropped", 0) == 0 ||
        line.rfind("tumble_step_seconds_sum", 0) == 0 ||
        line.rfind("tumble_step_seconds_count", 0) == 0)
      std::printf("  %s\n", line.c_str());
  return 0;
}
