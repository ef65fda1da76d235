#include "sim_pool.hpp"

#include <algorithm>

#include "sim_loop.hpp"

namespace tumble::server {

SimPool::SimPool(unsigned threads) {
  threads = std::max(1u, threads);
  threads_.reserve(threads);
  for (unsigned i = 0; i < threads; ++i) threads_.emplace_back([this] { run(); });
}

SimPool::~SimPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  work_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void SimPool::add(SimLoop& loop) {
  {
    std::lock_guard lock(mutex_);
    loops_.try_emplace(&loop, Entry{Clock::now()});
  }
  work_.notify_one();
}

void SimPool::remove(SimLoop& loop) {
  std::unique_lock lock(mutex_);
  const auto it = loops_.find(&loop);
  if (it == loops_.end()) return;
  it->second.removing = true;  // No thread picks it up from now on.
  idle_.wait(lock, [&] { return !it->second.running; });
  loops_.erase(it);
}

void SimPool::wake(SimLoop& loop) {
  {
    std::lock_guard lock(mutex_);
    const auto it = loops_.find(&loop);
    if (it == loops_.end() || it->second.removing) return;
    if (it->second.running) {
      it->second.woken = true;
      return;
    }
    it->second.due = std::min(it->second.due, Clock::now());
  }
  work_.notify_one();
}

// The idle loop whose work has been due longest (null if none is idle).
std::pair<SimLoop* const, SimPool::Entry>* SimPool::next_due() {
  std::pair<SimLoop* const, Entry>* best = nullptr;
  for (auto& entry : loops_)
    if (!entry.second.running && !entry.second.removing &&
        (!best || entry.second.due < best->second.due))
      best = &entry;
  return best;
}

// Earliest-due first. A loop that finished behind the clock (its next step is already due)
// is queued at the instant its service ended, not at the earlier instant its step was due:
// otherwise a world that can never catch up would always be the earliest and starve every
// other world on its thread. So overdue worlds take turns, and each service is bounded by
// SimLoop::kStepBudget, which bounds how late a light world's step can be.
void SimPool::run() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    auto* entry = next_due();
    if (!entry || entry->second.due == Clock::time_point::max()) {
      work_.wait(lock);
      continue;
    }
    if (entry->second.due > Clock::now()) {
      work_.wait_until(lock, entry->second.due);
      continue;
    }
    entry->second.running = true;
    entry->second.woken = false;
    SimLoop& loop = *entry->first;
    lock.unlock();
    const Clock::time_point next = loop.service();
    lock.lock();
    const Clock::time_point now = Clock::now();
    // `entry` is still valid: remove() waits for running == false before erasing.
    Entry& e = entry->second;
    e.running = false;
    if (!e.removing) e.due = e.woken ? now : std::max(next, now);
    idle_.notify_all();
  }
}

}  // namespace tumble::server
