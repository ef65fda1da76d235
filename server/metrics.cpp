#include "metrics.hpp"

#include <time.h>

#include <sstream>

#include "snapshot.hpp"

namespace tumble::server {
namespace {

void add(std::atomic<double>& a, double x) {
  double old = a.load(std::memory_order_relaxed);
  while (!a.compare_exchange_weak(old, old + x, std::memory_order_relaxed)) {
  }
}

void gauge(std::ostream& out, const char* name, const char* help, double value) {
  out << "# HELP " << name << ' ' << help << "\n# TYPE " << name << " gauge\n"
      << name << ' ' << value << '\n';
}

void counter(std::ostream& out, const char* name, const char* help, double value) {
  out << "# HELP " << name << ' ' << help << "\n# TYPE " << name << " counter\n"
      << name << ' ' << value << '\n';
}

}  // namespace

std::string render_world_gauges(const std::vector<WorldGauges>& worlds) {
  std::ostringstream out;
  out.precision(17);
  gauge(out, "tumble_worlds", "Worlds on this server, the default counted.",
        static_cast<double>(worlds.size()));
  const auto family = [&](const char* name, const char* help, auto value) {
    out << "# HELP " << name << ' ' << help << "\n# TYPE " << name << " gauge\n";
    for (const WorldGauges& w : worlds)
      out << name << "{world=\"" << w.id << "\"} " << static_cast<double>(value(w)) << '\n';
  };
  family("tumble_world_real_time_factor", "Simulated seconds per wall second, per world.",
         [](const WorldGauges& w) { return w.real_time_factor; });
  family("tumble_world_sim_time_seconds", "Simulated time since the last reset, per world.",
         [](const WorldGauges& w) { return w.time; });
  family("tumble_world_bodies", "Bodies, per world.",
         [](const WorldGauges& w) { return w.bodies; });
  family("tumble_world_bodies_awake", "Bodies integrated each step, per world.",
         [](const WorldGauges& w) { return w.awake; });
  family("tumble_world_viewers", "Connected WebSocket viewers, per world.",
         [](const WorldGauges& w) { return w.viewers; });
  family("tumble_world_paused", "1 while the world is paused.",
         [](const WorldGauges& w) { return w.paused ? 1 : 0; });
  family("tumble_world_history_bytes",
         "Estimated bytes of the world's timeline (checkpoints, log), at most --history-mb.",
         [](const WorldGauges& w) { return w.history_bytes; });
  return out.str();
}

double thread_cpu_seconds() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void Metrics::observe_step(double seconds) {
  std::size_t i = 0;
  while (i < kStepBuckets.size() && seconds > kStepBuckets[i]) ++i;
  step_buckets_[i].fetch_add(1, std::memory_order_relaxed);
  step_count_.fetch_add(1, std::memory_order_relaxed);
  add(step_seconds_sum_, seconds);
}

void Metrics::add_dropped_time(double seconds) { add(dropped_time_, seconds); }

void Metrics::add_stream_cpu(double seconds) { add(stream_cpu_, seconds); }

void Metrics::count_http(unsigned status) {
  const unsigned c = status / 100;
  if (c < http_by_class_.size()) http_by_class_[c].fetch_add(1, std::memory_order_relaxed);
}

std::string Metrics::render(const Snapshot& s, std::size_t viewers) const {
  std::ostringstream out;
  out.precision(17);
  out << "# HELP tumble_step_seconds Wall time of one physics step.\n"
         "# TYPE tumble_step_seconds histogram\n";
  std::uint64_t cumulative = 0;
  for (std::size_t i = 0; i < kStepBuckets.size(); ++i) {
    cumulative += step_buckets_[i].load(std::memory_order_relaxed);
    std::ostringstream le;
    le << kStepBuckets[i];
    out << "tumble_step_seconds_bucket{le=\"" << le.str() << "\"} " << cumulative << '\n';
  }
  cumulative += step_buckets_.back().load(std::memory_order_relaxed);
  out << "tumble_step_seconds_bucket{le=\"+Inf\"} " << cumulative << '\n'
      << "tumble_step_seconds_sum " << step_seconds_sum_.load(std::memory_order_relaxed) << '\n'
      << "tumble_step_seconds_count " << cumulative << '\n';
  gauge(out, "tumble_real_time_factor", "Simulated seconds per wall second (0 while paused).",
        s.real_time_factor);
  gauge(out, "tumble_sim_time_seconds", "Simulated time since the last reset.", s.time);
  gauge(out, "tumble_paused", "1 while the simulation is paused.", s.paused ? 1 : 0);
  gauge(out, "tumble_bodies", "Bodies in the scene.", static_cast<double>(s.bodies->size()));
  gauge(out, "tumble_bodies_awake", "Bodies integrated each step.", static_cast<double>(s.awake));
  gauge(out, "tumble_bodies_frozen", "Bodies frozen after going non-finite.",
        static_cast<double>(s.frozen));
  gauge(out, "tumble_energy_joules", "Total energy of the scene.", s.energy);
  gauge(out, "tumble_viewers", "Connected WebSocket viewers.", static_cast<double>(viewers));
  counter(out, "tumble_frames_sent_total", "Frames handed to WebSocket writers.",
          static_cast<double>(frames_sent()));
  counter(out, "tumble_frames_dropped_total",
          "Frames replaced by a newer one before a slow viewer took them.",
          static_cast<double>(frames_dropped()));
  counter(out, "tumble_frame_ticks_skipped_total",
          "Frame ticks (20 ms) skipped because the frame timer woke over a period late.",
          static_cast<double>(ticks_skipped()));
  counter(out, "tumble_frame_bytes_total", "Frame payload bytes written to viewers.",
          static_cast<double>(frame_bytes()));
  gauge(out, "tumble_frames_in_flight", "Frames being written now (at most one per viewer).",
        static_cast<double>(frames_in_flight()));
  counter(out, "tumble_stream_cpu_seconds_total",
          "Thread CPU time spent making and encoding frames.", stream_cpu());
  counter(out, "tumble_dropped_sim_seconds_total",
          "Simulated time skipped because stepping fell behind real time.",
          dropped_time_.load(std::memory_order_relaxed));
  counter(out, "tumble_step_failures_total",
          "Steps or commands that failed to allocate memory (the simulation paused).",
          static_cast<double>(step_failures()));
  out << "# HELP tumble_http_responses_total HTTP responses by status class.\n"
         "# TYPE tumble_http_responses_total counter\n";
  for (std::size_t c = 1; c < http_by_class_.size(); ++c)
    out << "tumble_http_responses_total{code=\"" << c << "xx\"} "
        << http_by_class_[c].load(std::memory_order_relaxed) << '\n';
  return out.str();
}

}  // namespace tumble::server
