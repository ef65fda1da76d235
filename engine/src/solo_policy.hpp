#pragma once
/// When a WorkerPool's step runs on its caller alone: decided step by step from how long the
/// last step's threads were held up.
#include <cstdint>

namespace tumble {

/// Whether the next step of a pool runs on its caller alone, decided step by step from how
/// long the threads of the last one were held up (WorkerPool::Busy). A step's jobs wait for
/// every chunk a thread has taken, and each contact of a sweep for its bodies' earlier
/// contacts: when the machine has more runnable threads than cores, a worker descheduled
/// inside a chunk holds the others for its time slice (milliseconds), and the caller loses its
/// own core part of the time. `pile` on two threads beside one busy process took 4.2–6.1 ms a
/// step against one thread's 3.2–3.4. A step held up for more than a quarter of its time, and
/// for longer than kLeastStall (a worker woken from its sleep holds an early step up ~0.25 ms;
/// a time slice is longer), sends the next ones to the caller alone: the same bits, since
/// every stage gives the same results on any thread count. Then one step shares again to see
/// whether the cores are free; a stall soon after it doubles the stretch alone (2 steps up to
/// 512), so a machine that stays busy costs one held-up step in hundreds. Plain data; used by
/// the pool's owner thread only.
class SoloPolicy {
 public:
  /// Steps alone after the first stall, and at most.
  static constexpr std::uint32_t kFirst = 2, kMost = 512;
  /// Shared steps without a stall after which the next stall starts again from kFirst.
  static constexpr std::uint32_t kRecent = 8;
  /// The least held-up time of a step that counts as a stall, ns.
  static constexpr std::uint64_t kLeastStall = 500'000;

  /// Called once a step ends with its wall time and the time its threads spent held up
  /// (ns, summed over threads); returns whether the next step runs on the caller alone.
  bool next_solo(std::uint64_t wall_ns, std::uint64_t stalled_ns);

 private:
  std::uint32_t left_ = 0;          // steps alone still to run
  std::uint32_t length_ = kFirst;   // the last stretch alone
  std::uint32_t since_ = kRecent;   // shared steps since the last stretch alone (saturating)
};

}  // namespace tumble
