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
    const auto [it, added] = loops_.try_emplace(&loop, Entry{Clock::time_point::max()});
    if (added) queue(&loop, it->second, Clock::now());
  }
  work_.notify_one();
}

void SimPool::remove(SimLoop& loop) {
  std::unique_lock lock(mutex_);
  const auto it = loops_.find(&loop);
  if (it == loops_.end()) return;
  it->second.removing = true;  // No thread picks it up from now on.
  ready_.erase({it->second.due, &loop});
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
    queue(&loop, it->second, std::min(it->second.due, Clock::now()));
  }
  work_.notify_one();
}

// (Re)places an idle loop in the ready queue at `due` (max: not queued; only a wake brings
// work). Under mutex_.
void SimPool::queue(SimLoop* loop, Entry& entry, Clock::time_point due) {
  ready_.erase({entry.due, loop});
  entry.due = due;
  if (due != Clock::time_point::max()) ready_.emplace(due, loop);
}

// Earliest-due first. A loop that finished behind the clock (its next step is already due)
// is queued at the instant its service ended, not at the earlier instant its step was due:
// otherwise a world that can never catch up would always be the earliest and starve every
// other world on its thread. So overdue worlds take turns, and each service is bounded by
// SimLoop::kStepBudget, which bounds how late a light world's step can be.
void SimPool::run() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    if (ready_.empty()) {
      work_.wait(lock);
      continue;
    }
    const auto [due, loop] = *ready_.begin();
    if (due > Clock::now()) {
      work_.wait_until(lock, due);
      continue;
    }
    ready_.erase(ready_.begin());
    Entry& entry = loops_.at(loop);  // Stays valid: remove() waits for running == false.
    entry.running = true;
    entry.woken = false;
    lock.unlock();
    const Clock::time_point next = loop->service();
    lock.lock();
    const Clock::time_point now = Clock::now();
    entry.running = false;
    entry.due = Clock::time_point::max();  // Not in ready_ while it ran.
    if (!entry.removing) queue(loop, entry, entry.woken ? now : std::max(next, now));
    if (entry.removing) idle_.notify_all();
  }
}

}  // namespace tumble::server
