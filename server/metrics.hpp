#pragma once
/// Counters and gauges for GET /metrics (Prometheus text format). Thread-safe: every field is
/// an atomic written by one kind of thread (the simulation thread or the I/O threads).
#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace tumble::server {

struct Snapshot;

/// One world's gauges for /metrics.
struct WorldGauges {
  std::string id;                ///< World id.
  double real_time_factor = 0;   ///< Sim s per wall s (0 paused).
  double time = 0;               ///< Sim time, s.
  std::size_t bodies = 0;        ///< Bodies.
  std::size_t awake = 0;         ///< Bodies awake.
  std::size_t viewers = 0;       ///< WebSocket viewers.
  bool paused = false;           ///< Paused.
  std::size_t history_bytes = 0; ///< Estimated bytes of its timeline.
};

/// The per-world gauges (label world="id") and tumble_worlds, Prometheus text.
std::string render_world_gauges(const std::vector<WorldGauges>& worlds);

/// CPU time of the calling thread, s (CLOCK_THREAD_CPUTIME_ID).
double thread_cpu_seconds();

/// Server-wide metrics.
class Metrics {
 public:
  /// Upper bounds of the step-time histogram buckets, seconds (then +Inf).
  static constexpr std::array<double, 10> kStepBuckets{1e-6, 1e-5, 5e-5, 1e-4, 5e-4,
                                                       1e-3, 5e-3, 1e-2, 5e-2, 1e-1};

  /// Records the wall time of one World::step, seconds (simulation thread).
  void observe_step(double seconds);
  /// Adds simulated seconds dropped because the loop fell behind (simulation thread).
  void add_dropped_time(double seconds);
  /// A frame was handed to a session's writer.
  void count_frame_sent() { frames_sent_.fetch_add(1, std::memory_order_relaxed); }
  /// A queued frame was replaced by a newer one before it could be written.
  void count_frame_dropped() { frames_dropped_.fetch_add(1, std::memory_order_relaxed); }
  /// `n` frame ticks were skipped because the frame timer woke over a period late (stream strand).
  void count_ticks_skipped(std::uint64_t n) { ticks_skipped_.fetch_add(n, std::memory_order_relaxed); }
  /// Frame ticks skipped so far (all worlds).
  std::uint64_t ticks_skipped() const { return ticks_skipped_.load(std::memory_order_relaxed); }
  /// Frames sent so far (all sessions).
  std::uint64_t frames_sent() const { return frames_sent_.load(std::memory_order_relaxed); }
  /// Frames dropped so far (all sessions).
  std::uint64_t frames_dropped() const { return frames_dropped_.load(std::memory_order_relaxed); }
  /// Adds `bytes` of frames written to viewers (WebSocket payload, before any compression).
  void add_frame_bytes(std::size_t bytes) { frame_bytes_.fetch_add(bytes, std::memory_order_relaxed); }
  /// Frame payload bytes so far (all sessions).
  std::uint64_t frame_bytes() const { return frame_bytes_.load(std::memory_order_relaxed); }
  /// A session started (+1) or finished (−1) writing a frame.
  void add_frames_in_flight(int n) { frames_in_flight_.fetch_add(n, std::memory_order_relaxed); }
  /// Frames being written now, all sessions (each holds at most one).
  std::int64_t frames_in_flight() const { return frames_in_flight_.load(std::memory_order_relaxed); }
  /// Adds thread CPU time spent making and encoding frames (broadcaster and encoders), s.
  void add_stream_cpu(double seconds);
  /// Stream CPU seconds so far.
  double stream_cpu() const { return stream_cpu_.load(std::memory_order_relaxed); }
  /// A step or command failed to allocate memory (simulation thread).
  void count_step_failure() { step_failures_.fetch_add(1, std::memory_order_relaxed); }
  /// Allocation failures so far.
  std::uint64_t step_failures() const { return step_failures_.load(std::memory_order_relaxed); }
  /// A request was answered with `status`.
  void count_http(unsigned status);

  /// The Prometheus text exposition, with gauges read from `latest` and `viewers`.
  std::string render(const Snapshot& latest, std::size_t viewers) const;

 private:
  std::array<std::atomic<std::uint64_t>, kStepBuckets.size() + 1> step_buckets_{};
  std::atomic<std::uint64_t> step_count_{0};
  std::atomic<double> step_seconds_sum_{0.0};
  std::atomic<double> dropped_time_{0.0};
  std::atomic<std::uint64_t> frames_sent_{0};
  std::atomic<std::uint64_t> frames_dropped_{0};
  std::atomic<std::uint64_t> ticks_skipped_{0};
  std::atomic<std::uint64_t> step_failures_{0};
  std::atomic<std::uint64_t> frame_bytes_{0};
  std::atomic<std::int64_t> frames_in_flight_{0};
  std::atomic<double> stream_cpu_{0.0};
  std::array<std::atomic<std::uint64_t>, 6> http_by_class_{};  // 0xx..5xx
};

}  // namespace tumble::server
