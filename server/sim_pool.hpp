#pragma once
/// The simulation threads every world of a server shares. Each world keeps its own fixed-step
/// real-time loop (SimLoop::service runs what is due and says when it next has work); the
/// pool runs the loop whose work has waited longest, one thread per loop at a time, so a
/// world never runs on two threads at once and a heavy world, always behind, takes only the
/// time the others leave (it cannot starve them: see SimPool::run).
///
/// Usage:
///   SimPool pool(2);
///   SimLoop sim(scene, metrics);
///   pool.add(sim);      // it starts stepping
///   …
///   sim.stop();         // takes it out of the pool again (also done by ~SimLoop)
#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "snapshot.hpp"

namespace tumble::server {

class SimLoop;

/// A fixed set of threads stepping any number of SimLoops. Thread-safe.
class SimPool {
 public:
  /// Starts `threads` threads (at least 1).
  explicit SimPool(unsigned threads);
  /// Stops and joins the threads; loops still added are no longer serviced.
  ~SimPool();
  SimPool(const SimPool&) = delete;
  SimPool& operator=(const SimPool&) = delete;

  /// Starts servicing `loop` (its first service is due now). The loop must outlive its
  /// removal; SimLoop::stop removes it.
  void add(SimLoop& loop);
  /// Stops servicing `loop`; returns once no thread runs it, and none will again. Idempotent.
  void remove(SimLoop& loop);
  /// `loop` has work now (a command arrived). Thread-safe; cheap.
  void wake(SimLoop& loop);
  /// Threads in the pool.
  unsigned threads() const { return static_cast<unsigned>(threads_.size()); }

 private:
  struct Entry {
    Clock::time_point due;  // When its next work is due (max: only a wake brings work).
    bool running = false;   // A thread is in its service() now.
    bool woken = false;     // A wake came while it ran: due again at once.
    bool removing = false;  // remove() waits for its service to end.
  };

  void run();
  void queue(SimLoop* loop, Entry& entry, Clock::time_point due);

  std::mutex mutex_;
  std::condition_variable work_;  // A loop became due, or the pool stops.
  std::condition_variable idle_;  // A service ended (remove waits on it).
  std::unordered_map<SimLoop*, Entry> loops_;
  // The idle loops by due time (a running or removed loop is not in it): the next one to run
  // is the first, in O(log n) for a thousand worlds as for one.
  std::set<std::pair<Clock::time_point, SimLoop*>> ready_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace tumble::server
