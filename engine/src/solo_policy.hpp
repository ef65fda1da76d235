#pragma once
/// When a WorkerPool's step runs on its caller alone: decided step by step from how long the
/// last step's threads were held up, and from timed trials while its cores are far apart.
#include <array>
#include <cstdint>

namespace tumble {

/// Whether the next step of a pool runs on its caller alone: the same bits either way, since
/// every stage gives the same results on any thread count. Two causes send steps there.
///
/// *Held up.* A step's jobs wait for every chunk a thread has taken, and each contact of a
/// sweep for its bodies' earlier contacts: when the machine has more runnable threads than
/// cores, a worker descheduled inside a chunk holds the others for its time slice
/// (milliseconds), and the caller loses its own core part of the time. `pile` on two threads
/// beside one busy process took 4.2–6.1 ms a step against one thread's 3.2–3.4. A step held
/// up for more than a quarter of its time, and for longer than kLeastStall (a worker woken
/// from its sleep holds an early step up ~0.25 ms; a time slice is longer), sends the next
/// ones to the caller alone. Then one step shares again to see whether the cores are free; a
/// stall soon after it doubles the stretch alone (2 steps up to 512), so a machine that stays
/// busy costs one held-up step in hundreds.
///
/// *Far cores.* A virtual machine's two cores can sit where a cache line takes 330 ns to go
/// there and back instead of 60 (this project's machine, for minutes at a time); the sweeps
/// hand every body between the threads, and `pile` on two threads then took 3.8 ms a step
/// against one thread's 3.2, though neither thread waited or lost its core. So every
/// kProbeEvery shared steps the pool times that round trip (WorkerPool::round_trip_ns); past
/// kFarRoundTrip, kTrialSteps steps run alone and are timed against the shared steps before
/// and after them (the mean of each side's fastest of three: a steady trend moves both
/// sides alike). The first step of each side is not timed: it brings the working set over
/// from the other core's cache. Alone faster by a twentieth wins a stretch alone (kWonFirst
/// steps). After it, four shared steps and a round trip: still far, the stretch's last steps
/// stand against those shared ones, and a second win doubles the stretch (up to kMost). A
/// lost trial doubles the wait for the next (up to kMost shared steps), so a scene that
/// shares well on far cores pays one trial in hundreds of steps. Near cores never start one.
///
/// Plain data; used by the pool's owner thread only.
class SoloPolicy {
 public:
  /// Steps alone after the first stall, and at most (also the longest wait between trials).
  static constexpr std::uint32_t kFirst = 2, kMost = 512;
  /// Shared steps without a stall after which the next stall starts again from kFirst.
  static constexpr std::uint32_t kRecent = 8;
  /// The least held-up time of a step that counts as a stall, ns.
  static constexpr std::uint64_t kLeastStall = 500'000;
  /// A caller–worker round trip past which the cores count as far, ns: a pair of cores under
  /// one cache shares a line in under 100 ns; 330 where this machine's were apart.
  static constexpr std::uint64_t kFarRoundTrip = 200;
  /// Shared steps between round trips; steps alone in a trial (the first not timed); steps
  /// alone after the first trial won.
  static constexpr std::uint32_t kProbeEvery = 16, kTrialSteps = 4, kWonFirst = 16;
  /// The shortest step after which the pool times a round trip, ns: one takes 1–6 µs, under
  /// 0.4 % of this every kProbeEvery steps (`pyramid`'s steps are ~0.45 ms, `tower`'s 0.01).
  static constexpr std::uint64_t kLeastProbed = 100'000;

  /// A policy whose cores count as far past `far_round_trip_ns` and whose steps count as held
  /// up past `least_stall_ns` (tests set them to force trials, and to keep stalls out of one).
  explicit SoloPolicy(std::uint64_t far_round_trip_ns = kFarRoundTrip,
                      std::uint64_t least_stall_ns = kLeastStall)
      : far_round_trip_ns_(far_round_trip_ns), least_stall_ns_(least_stall_ns) {}

  /// Called once a step ends with its wall time and the time its threads spent held up
  /// (ns, summed over threads); returns whether the next step runs on the caller alone.
  bool next_solo(std::uint64_t wall_ns, std::uint64_t stalled_ns);
  /// True when the step just ended was shared and the pool should now time its round trip.
  bool wants_round_trip() const;
  /// Takes the round trip timed after a shared step (ns; 0: no worker answered); returns
  /// whether the next step runs alone, as the first of a trial.
  bool after_round_trip(std::uint64_t round_trip_ns);

 private:
  /// A trial step's end; returns whether the next step runs alone.
  bool trial_step(std::uint64_t wall_ns);
  /// Steps alone (`alone_ns`, the fastest) against shared ones before and after (the mean of
  /// the fastest of each side), ns; true: a stretch alone follows.
  bool verdict(std::uint64_t before_ns, std::uint64_t after_ns, std::uint64_t alone_ns);

  std::uint64_t far_round_trip_ns_;
  std::uint64_t least_stall_ns_;
  std::uint32_t left_ = 0;          // steps alone still to run (a stall's or a won trial's)
  std::uint32_t length_ = kFirst;   // the last stretch alone after a stall
  std::uint32_t since_ = kRecent;   // shared steps since the last stretch alone (saturating)
  std::uint32_t shared_ = 0;        // shared steps in a row (saturating at kMost)
  std::array<std::uint64_t, 3> recent_{};  // the last shared steps' wall times, ns
  std::uint32_t until_probe_ = 0;   // shared steps before the next round trip
  std::uint32_t gap_ = kProbeEvery; // shared steps between round trips (doubles on a lost trial)
  std::uint32_t trial_left_ = 0;    // steps of a trial still to run alone
  std::uint64_t trial_best_ = 0;    // the fastest timed step of the trial, ns
  std::uint64_t before_best_ = 0;   // the fastest of recent_ when the trial began, ns
  std::uint32_t after_left_ = 0;    // shared steps after a trial still to run before its verdict
  std::uint32_t won_ = 0;           // the last won trial's stretch (0: the last trial lost)
  bool won_stretch_ = false;        // the stretch alone under way follows a won trial
  bool recheck_ = false;            // a won stretch ended: the next round trip decides again
  std::array<std::uint64_t, 3> alone_{};  // the won stretch's last steps' wall times, ns
};

}  // namespace tumble
