#include "worker_pool.hpp"

#include <algorithm>
#include <ctime>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace tumble {
namespace {

// A step submits its jobs microseconds apart, and a futex wake-up costs a few microseconds
// and a context switch: workers poll for a while before they sleep, as Box2D v3's task system
// and Jolt's job system do between the jobs of a step. A pause takes ~25 ns on this project's
// machine: kSpinRounds is ~25 µs, kBusySpinRounds ~0.2 ms. The longer poll holds only while a
// step is under way (WorkerPool::Busy): `pile`'s serial stretches (islands ~35 µs, the
// colouring, shock propagation's height order ~80 µs) outlast the short one, and its worker
// slept and was woken 5.2 times a step; with the longer poll 0.5 times, and two threads'
// step 3.12 → 3.02 ms (docs/engine.md, "Polling through the step"). Between steps (a server
// steps 60 times a second) the short poll lets the workers sleep.
constexpr int kSpinRounds = 1 << 10;
constexpr int kBusySpinRounds = 1 << 13;

/// CPU time of the calling thread, ns (a system call, ~1 µs on this project's machine).
std::uint64_t thread_cpu_ns() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<std::uint64_t>(t.tv_sec) * 1'000'000'000u +
         static_cast<std::uint64_t>(t.tv_nsec);
}

void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  _mm_pause();
#else
  std::this_thread::yield();
#endif
}

/// Waits until ready(): spins, then yields. Returns how long it yielded, ns: a wait that
/// outlasts its spinning reads the clock when it starts to yield and when it ends; shorter
/// waits read no clock and return 0.
template <typename Ready>
std::uint64_t wait_until(Ready ready) {
  for (int spins = 0; spins < kSpinRounds; ++spins) {
    if (ready()) return 0;
    cpu_relax();
  }
  const auto start = std::chrono::steady_clock::now();
  while (!ready()) std::this_thread::yield();
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now() - start)
                                        .count());
}

}  // namespace

// Only the long waits count as held up.
void WorkerPool::wait_turn(std::uint32_t& counter, std::uint32_t turn) {
  const std::atomic_ref<std::uint32_t> c(counter);
  count_stall(wait_until([&] { return c.load(std::memory_order_acquire) == turn; }));
}

void WorkerPool::count_stall(std::uint64_t ns) {
  if (ns > 0) stalled_ns_.fetch_add(ns, std::memory_order_relaxed);
}

// A pool without workers reads no clock. The caller's CPU time is a system call (~1 µs on
// this project's machine, a tenth of `tower`'s step on two threads): it is read only after a
// step long enough to be held up past kLeastStall, as the next is likely to be.
void WorkerPool::begin_step() {
  busy_.store(true, std::memory_order_relaxed);
  if (workers_.empty()) return;
  step_start_ = std::chrono::steady_clock::now();
  step_cpu_start_ = last_wall_ns_ > SoloPolicy::kLeastStall ? thread_cpu_ns() : 0;
}

// The step's held-up time: the caller's time off its core (descheduled, or asleep until a
// worker left a job; its wall time less its CPU time) and every thread's long waits.
void WorkerPool::end_step() {
  if (workers_.empty()) return busy_.store(false, std::memory_order_relaxed);
  const auto wall = static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() -
                                                           step_start_)
          .count());
  std::uint64_t stalled = stalled_ns_.exchange(0, std::memory_order_relaxed);
  if (step_cpu_start_ > 0) {
    const std::uint64_t cpu = thread_cpu_ns() - step_cpu_start_;
    stalled += wall > cpu ? wall - cpu : 0;
  }
  last_wall_ns_ = wall;
  solo_ = policy_.next_solo(wall, stalled);
  // A round trip (1–6 µs) only after a step past kLeastProbed, while the workers still poll.
  if (!solo_ && wall > SoloPolicy::kLeastProbed && policy_.wants_round_trip()) {
    const std::uint64_t round_trip = round_trip_ns();
    round_trips_ += round_trip > 0;
    solo_ = policy_.after_round_trip(round_trip);
  }
  busy_.store(false, std::memory_order_relaxed);
}

// The ball is one word on a line of its own; the clock is read around all kBounces trips
// (a clock read costs about what a near round trip does). A worker that does not answer a
// ball in kSpinRounds is not polling (or went to sleep between two balls): the caller takes
// the ball back, unless the worker took it meanwhile; either way it ends even.
std::uint64_t WorkerPool::round_trip_ns() {
  if (workers_.empty()) return 0;
  const auto start = std::chrono::steady_clock::now();
  for (int b = 0; b < kBounces; ++b) {
    std::uint32_t ball = bounce_.fetch_add(1) + 1;
    int spins = 0;
    while (bounce_.load(std::memory_order_acquire) == ball) {
      if (++spins > kSpinRounds) {
        bounce_.compare_exchange_strong(ball, ball + 1);
        return 0;
      }
      cpu_relax();
    }
  }
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                      std::chrono::steady_clock::now() - start)
                      .count();
  return static_cast<std::uint64_t>(ns) / kBounces;
}

void WorkerPool::answer_bounce() {
  std::uint32_t ball = bounce_.load(std::memory_order_relaxed);
  if ((ball & 1) != 0) bounce_.compare_exchange_strong(ball, ball + 1);
}

unsigned hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

WorkerPool::WorkerPool(unsigned threads, SoloPolicy policy) : policy_(policy) {
  const unsigned workers = threads > 1 ? threads - 1 : 0;
  workers_.reserve(workers);
  for (unsigned i = 0; i < workers; ++i) workers_.emplace_back([this] { worker_main(); });
}

WorkerPool::~WorkerPool() {
  stop_.store(true);
  job_.fetch_add(kGeneration);
  {
    std::lock_guard lock(mutex_);
  }
  work_ready_.notify_all();
  for (std::thread& t : workers_) t.join();
}

// The caller publishes the job, takes chunks like any worker, closes the job to latecomers and
// waits only for the workers inside it; only then may the job's fields change again.
void WorkerPool::run(std::size_t n, std::size_t grain, Thunk thunk, void* fn) {
  const std::size_t most = 4 * static_cast<std::size_t>(size());  // a few chunks per thread
  chunk_ = std::max(grain, (n + most - 1) / most);
  chunks_ = (n + chunk_ - 1) / chunk_;
  thunk_ = thunk;
  fn_ = fn;
  n_ = n;
  next_.store(0, std::memory_order_relaxed);
  const std::uint64_t generation = (job_.load(std::memory_order_relaxed) >> 17) + 1;
  job_.store(generation << 17);  // open, nobody inside; sequentially consistent with sleepers_
  if (sleepers_.load() > 0) {
    { std::lock_guard lock(mutex_); }  // a sleeper is now either waiting or sees the new job
    work_ready_.notify_all();
  }
  work();
  std::uint64_t state = job_.fetch_or(kClosed) | kClosed;
  for (int spins = 0; (state & kInside) != 0; state = job_.load(std::memory_order_acquire)) {
    if (++spins < kSpinRounds) {
      cpu_relax();
      continue;
    }
    std::unique_lock lock(mutex_);
    caller_waiting_.store(true);  // sequentially consistent: pairs with the worker's leaving
    job_left_.wait(lock, [&] { return (job_.load() & kInside) == 0; });
    caller_waiting_.store(false);
    state = job_.load(std::memory_order_acquire);
  }
}

// A for_each_phase job is a for_each job of one index per thread, each of which runs the
// phases: any thread that joins takes chunks of the current phase, and one that finds no chunk
// left waits for the phase's last chunk to finish before it moves on. A thread that runs the
// phases again (a late worker, or the caller taking a second index) finds every chunk taken
// and only passes through. The caller runs every phase itself when no worker joins.
void WorkerPool::run_phases(PhaseThunk thunk, void* fn) {
  phase_thunk_ = thunk;
  phase_fn_ = fn;
  run(size(), 1, [](void* pool, std::size_t slot, std::size_t) {
    static_cast<WorkerPool*>(pool)->work_phases(slot);
  }, this);
}

namespace {

/// Takes the next chunk of a phase from its front (from_back false) or its back; false when
/// none is left.
bool take_chunk(std::atomic<std::uint64_t>& ends, bool from_back, std::size_t& chunk) {
  std::uint64_t e = ends.load(std::memory_order_relaxed);
  for (;;) {
    const std::uint64_t front = e & 0xFFFFFFFFu, back = e >> 32;
    if (front >= back) return false;
    const std::uint64_t next = from_back ? e - (std::uint64_t{1} << 32) : e + 1;
    if (ends.compare_exchange_weak(e, next, std::memory_order_relaxed)) {
      chunk = from_back ? back - 1 : front;
      return true;
    }
  }
}

}  // namespace

// Slot 1 takes each phase's chunks from the back, every other slot from the front: the same
// thread then meets the same end of every colour, whose contacts (in pair order) hold much the
// same bodies from colour to colour, so a body's velocities stay in one core's cache instead
// of passing between cores in every phase.
void WorkerPool::work_phases(std::size_t slot) {
  const bool from_back = slot == 1;
  for (std::size_t p = 0; p < phase_count_; ++p) {
    Phase& ph = phases_[p];
    for (;;) {
      std::size_t c = 0;
      if (!take_chunk(ph.ends, from_back, c)) break;
      const std::size_t begin = c * ph.chunk;
      phase_thunk_(phase_fn_, p, begin, std::min(ph.n, begin + ph.chunk));
      ph.done.fetch_add(1, std::memory_order_release);
    }
    // Every chunk of phase p is taken; wait until they are done (their writes visible).
    if (!phase_barrier_) continue;
    count_stall(wait_until([&] { return ph.done.load(std::memory_order_acquire) >= ph.chunks; }));
  }
}

void WorkerPool::work() {
  for (;;) {
    const std::size_t c = next_.fetch_add(1, std::memory_order_relaxed);
    if (c >= chunks_) return;
    const std::size_t begin = c * chunk_;
    thunk_(fn_, begin, std::min(n_, begin + chunk_));
  }
}

void WorkerPool::worker_main() {
  std::uint64_t seen = job_.load() & ~(kClosed | kInside);
  for (;;) {
    std::uint64_t state = job_.load(std::memory_order_acquire);
    for (int spins = 0; (state & ~(kClosed | kInside)) == seen && !stop_.load();
         state = job_.load(std::memory_order_acquire)) {
      if (++spins < kSpinRounds ||
          (spins < kBusySpinRounds && busy_.load(std::memory_order_relaxed))) {
        answer_bounce();
        cpu_relax();
        continue;
      }
      std::unique_lock lock(mutex_);
      sleepers_.fetch_add(1);  // sequentially consistent: either run() sees us or we see it
      work_ready_.wait(lock, [&] {
        return (job_.load() & ~(kClosed | kInside)) != seen || stop_.load();
      });
      sleepers_.fetch_sub(1);
    }
    if (stop_.load()) return;
    seen = state & ~(kClosed | kInside);
    // Join unless the caller has closed the job (it finished without us).
    while ((state & kClosed) == 0 && (state & ~(kClosed | kInside)) == seen &&
           !job_.compare_exchange_weak(state, state + 1, std::memory_order_acquire))
      ;
    if ((state & kClosed) != 0 || (state & ~(kClosed | kInside)) != seen) continue;
    work();
    const std::uint64_t left = job_.fetch_sub(1) - 1;  // release: our chunks are visible
    if ((left & kInside) == 0 && caller_waiting_.load()) {
      { std::lock_guard lock(mutex_); }
      job_left_.notify_all();
    }
  }
}

}  // namespace tumble
