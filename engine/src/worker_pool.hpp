#pragma once
/// A small pool of worker threads for the stages of one World::step: `for_each` splits an
/// index range into chunks that the caller and the workers take in turn. Results never depend
/// on the thread count as long as each index writes only its own outputs (every stage that
/// uses the pool is written that way), so a World steps bit-identically on 1 or N threads.
/// One thread (the World's owner) submits work; the pool itself is not re-entrant.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "solo_policy.hpp"

namespace tumble {

/// Adds one to `counter` (release); only the thread whose turn it was may call it. With
/// WorkerPool::wait_turn, orders the items of a for_each_phase job run without barriers.
inline void pass_turn(std::uint32_t& counter) {
  std::atomic_ref<std::uint32_t> c(counter);
  c.store(c.load(std::memory_order_relaxed) + 1, std::memory_order_release);
}

/// Worker threads that spin briefly between jobs (a step submits a few hundred small jobs in
/// a row) and sleep on a futex otherwise. A worker that comes late finds the job done and
/// skips it: the caller never waits for a thread that has not started. A worker descheduled
/// inside a job does hold the others up; steps held up that way send the next ones to the
/// caller alone for a while (SoloPolicy), so a busy machine (more runnable threads than
/// cores) slows a step down to about one thread's pace, not far below; so do timed trials
/// while the cores are far apart (round_trip_ns). Owned by one World; not copyable.
class WorkerPool {
 public:
  /// A pool of `threads` − 1 workers plus the calling thread; threads ≥ 1 (1: no workers).
  /// `policy` decides which steps run on the caller alone.
  explicit WorkerPool(unsigned threads, SoloPolicy policy = SoloPolicy());
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  /// Threads of the pool, the caller included, as constructed.
  unsigned threads() const { return static_cast<unsigned>(workers_.size()) + 1; }
  /// Threads that share a job now, the caller included: threads(), or 1 for a step that runs
  /// on the caller alone (SoloPolicy). Stages choose their one-thread paths by it.
  unsigned size() const { return solo_ ? 1u : threads(); }
  /// True while steps run on the caller alone because the last shared one was held up.
  bool solo() const { return solo_; }

  /// The time a cache line takes from the caller to a polling worker and back, ns: the mean
  /// of kBounces round trips, or 0 when some ball went unanswered for ~25 µs (a worker asleep,
  /// descheduled, or none). Owner thread, between jobs.
  std::uint64_t round_trip_ns();
  /// Round trips timed at the ends of steps that a worker answered (SoloPolicy). Owner thread.
  std::uint64_t round_trips() const { return round_trips_; }

  /// Waits until `counter` (read atomically, acquire) equals `turn`: spins, then yields,
  /// counting a long wait as held up (SoloPolicy). Any thread of a job.
  void wait_turn(std::uint32_t& counter, std::uint32_t turn);

  /// While held (by the submitting thread, around one World::step), idle workers poll for the
  /// next job up to ~0.2 ms instead of ~25 µs before they sleep: a step's serial stretches
  /// between jobs outlast the short poll, and each then cost a wake-up. At its end, the step's
  /// wall time and waits decide whether the next step shares (SoloPolicy). Not nested.
  class Busy {
   public:
    /// Marks `pool` busy until destruction.
    explicit Busy(WorkerPool& pool) : pool_(pool) { pool_.begin_step(); }
    ~Busy() { pool_.end_step(); }
    Busy(const Busy&) = delete;
    Busy& operator=(const Busy&) = delete;

   private:
    WorkerPool& pool_;
  };

  /// Calls fn(begin, end) over [0, n) in chunks of at least `grain` indices, on this thread
  /// and the workers; returns when every chunk is done. Runs inline when n ≤ grain or the
  /// pool has no workers. Allocates nothing.
  template <typename Fn>
  void for_each(std::size_t n, std::size_t grain, Fn&& fn) {
    if (n == 0) return;
    if (size() == 1 || n <= grain) return fn(std::size_t{0}, n);
    run(n, grain, &call<Fn>, &fn);
  }

  /// Calls fn(phase, begin, end) over [0, size(phase)) for phase = 0 … phases − 1 in turn,
  /// each phase in chunks of at least `grain` shared among the threads; a phase starts on any
  /// thread only once every chunk of the one before is done. One job for all the phases: a
  /// thread waits between phases on a counter (a fraction of a microsecond) where a job per
  /// phase cost the caller a publication, a close and a thread's idle chunk each. `size` is
  /// called once per phase, on the caller. Runs inline when the pool has no workers or the
  /// phases average under two chunks. Allocates only when `phases` grows. With `barrier`
  /// false a thread that finds no chunk left in a phase moves on at once: fn then orders
  /// its items itself (the contact sweep waits for each body's turn: wait_turn).
  template <typename Size, typename Fn>
  void for_each_phase(std::size_t phases, std::size_t grain, Size&& size, Fn&& fn,
                      bool barrier = true) {
    phase_barrier_ = barrier;
    if (this->size() == 1) {
      for (std::size_t p = 0; p < phases; ++p) fn(p, std::size_t{0}, static_cast<std::size_t>(size(p)));
      return;
    }
    const std::size_t chunks =
        plan_phases(phases, grain, [&](std::size_t p) { return static_cast<std::size_t>(size(p)); });
    // A phase of one chunk has nothing to share and its wait hands the bodies' velocities
    // between cores: when the phases average under two chunks (`tower`'s chain of contacts,
    // `pyramid`'s ~10 per colour) the caller runs them all, in the same order.
    if (chunks < 2 * phases) {
      for (std::size_t p = 0; p < phases; ++p) fn(p, std::size_t{0}, phases_[p].n);
      return;
    }
    run_phases(&call_phase<Fn>, &fn);
  }

 private:
  /// One phase of a for_each_phase job: its chunks, the two ends of those left and those done.
  struct Phase {
    std::size_t n = 0, chunk = 1, chunks = 0;
    alignas(64) std::atomic<std::uint64_t> ends{0};  // next chunk from the front | back << 32
    alignas(64) std::atomic<std::size_t> done{0};
  };
  using PhaseThunk = void (*)(void*, std::size_t, std::size_t, std::size_t);
  template <typename Fn>
  static void call_phase(void* fn, std::size_t phase, std::size_t begin, std::size_t end) {
    (*static_cast<Fn*>(fn))(phase, begin, end);
  }
  /// Sizes and chunks the phases; returns their chunks in all.
  template <typename Size>
  std::size_t plan_phases(std::size_t phases, std::size_t grain, Size&& size) {
    if (phase_capacity_ < phases) {
      phase_capacity_ = std::max(phases, 2 * phase_capacity_);
      phases_ = std::make_unique<Phase[]>(phase_capacity_);
    }
    phase_count_ = phases;
    const std::size_t most = 4 * static_cast<std::size_t>(this->size());
    std::size_t chunks = 0;
    for (std::size_t p = 0; p < phases; ++p) {
      Phase& ph = phases_[p];
      ph.n = size(p);
      ph.chunk = std::max<std::size_t>(std::max<std::size_t>(grain, 1), (ph.n + most - 1) / most);
      ph.chunks = (ph.n + ph.chunk - 1) / ph.chunk;
      ph.ends.store(static_cast<std::uint64_t>(ph.chunks) << 32, std::memory_order_relaxed);
      ph.done.store(0, std::memory_order_relaxed);
      chunks += ph.chunks;
    }
    return chunks;
  }
  void run_phases(PhaseThunk thunk, void* fn);
  void work_phases(std::size_t slot);

  using Thunk = void (*)(void*, std::size_t, std::size_t);
  template <typename Fn>
  static void call(void* fn, std::size_t begin, std::size_t end) {
    (*static_cast<Fn*>(fn))(begin, end);
  }
  void run(std::size_t n, std::size_t grain, Thunk thunk, void* fn);
  void work();
  void worker_main();
  /// Hands the caller's ball back (round_trip_ns) if it is out; any worker, while polling.
  void answer_bounce();
  void begin_step();
  void end_step();
  /// Adds `ns` of waiting to the step's held-up time (any thread).
  void count_stall(std::uint64_t ns);

  std::unique_ptr<Phase[]> phases_;  // the phases of the current for_each_phase job
  std::size_t phase_capacity_ = 0;
  std::size_t phase_count_ = 0;
  bool phase_barrier_ = true;  // a phase starts once the one before is done
  PhaseThunk phase_thunk_ = nullptr;
  void* phase_fn_ = nullptr;
  std::vector<std::thread> workers_;
  // The job: written by the caller while no worker has joined, read by workers that joined it.
  Thunk thunk_ = nullptr;
  void* fn_ = nullptr;
  std::size_t n_ = 0;
  std::size_t chunk_ = 0;
  std::size_t chunks_ = 0;
  alignas(64) std::atomic<std::size_t> next_{0};  // next chunk to take
  // The job's generation (bits 17 and up), whether it is closed to newcomers (bit 16) and how
  // many workers are inside it (bits 0–15). One word, so that joining is one compare-exchange.
  alignas(64) std::atomic<std::uint64_t> job_{kClosed};
  // Sleeping is a mutex and condition variables (std::atomic::wait of GCC 12 loses wake-ups
  // here). A thread counts itself in sleepers_ or caller_waiting_ under the mutex before it
  // checks its condition; the other side changes job_ first, then takes the mutex to notify
  // only when someone may sleep.
  std::mutex mutex_;
  std::condition_variable work_ready_;       // job_ moved to a new generation (or stop)
  std::condition_variable job_left_;         // the last worker left a closed job
  std::atomic<unsigned> sleepers_{0};        // workers asleep on work_ready_
  std::atomic<bool> caller_waiting_{false};  // the caller asleep on job_left_
  std::atomic<bool> stop_{false};
  std::atomic<bool> busy_{false};  // a step is under way: poll longer (Busy)
  // Held-up time of the step under way (ns, any thread), its start, and what it decides
  // (the owner's thread only).
  alignas(64) std::atomic<std::uint64_t> stalled_ns_{0};
  std::chrono::steady_clock::time_point step_start_{};
  std::uint64_t step_cpu_start_ = 0;  // the caller's CPU time at the step's start, ns (0: unread)
  std::uint64_t last_wall_ns_ = 0;    // the last step's wall time, ns
  // round_trip_ns's ball: odd while it waits for a worker, who makes it even.
  alignas(64) std::atomic<std::uint32_t> bounce_{0};
  std::uint64_t round_trips_ = 0;  // round trips answered at the ends of steps
  SoloPolicy policy_;
  bool solo_ = false;
  static constexpr int kBounces = 16;
  static constexpr std::uint64_t kClosed = std::uint64_t{1} << 16;
  static constexpr std::uint64_t kInside = kClosed - 1;
  static constexpr std::uint64_t kGeneration = std::uint64_t{1} << 17;
};

/// Threads a World uses when asked for "as many as there are cores".
unsigned hardware_threads();

}  // namespace tumble
