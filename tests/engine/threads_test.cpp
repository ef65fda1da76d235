// Worker threads (World::set_threads, engine/src/worker_pool.hpp): every index of a job runs
// exactly once, and a World steps bit for bit the same on one thread as on several.
#include <atomic>
#include <chrono>
#include <cstring>
#include <numeric>
#include <thread>
#include <vector>

#include "../sanitized.hpp"
#include "world_fixture.hpp"
#include "worker_pool.hpp"

namespace tumble {
namespace {

using testing::bundled;

// Positions, orientations, momenta and activity of every body, compared byte for byte.
void expect_identical(const World& a, const World& b) {
  ASSERT_EQ(a.bodies().size(), b.bodies().size());
  for (std::size_t i = 0; i < a.bodies().size(); ++i) {
    const BodyState &x = a.bodies()[i].s, &y = b.bodies()[i].s;
    ASSERT_EQ(std::memcmp(x.x.data(), y.x.data(), sizeof(double) * 3), 0) << "x of body " << i;
    ASSERT_EQ(std::memcmp(x.R.data(), y.R.data(), sizeof(double) * 9), 0) << "R of body " << i;
    ASSERT_EQ(std::memcmp(x.P.data(), y.P.data(), sizeof(double) * 3), 0) << "P of body " << i;
    ASSERT_EQ(std::memcmp(x.L.data(), y.L.data(), sizeof(double) * 3), 0) << "L of body " << i;
    ASSERT_EQ(a.bodies()[i].activity, b.bodies()[i].activity) << "activity of body " << i;
  }
  EXPECT_EQ(a.total_impacts(), b.total_impacts());
}

// Steps `scene` on 1, 2 and 3 threads with the same impulses (zero kicks that keep islands
// awake, and one real kick) and checks after every step that the states agree.
void expect_same_on_any_thread_count(const Scene& scene, int steps) {
  std::vector<World> worlds;
  for (unsigned threads : {1u, 2u, 3u}) {
    worlds.emplace_back(scene);
    worlds.back().set_threads(threads);
    ASSERT_EQ(worlds.back().threads(), threads);
  }
  for (int i = 1; i <= steps; ++i) {
    for (World& w : worlds) {
      if (i % 15 == 0)
        for (std::size_t b = 0; b < w.bodies().size(); b += 7) w.apply_impulse(BodyId(b), Vec3::Zero());
      if (i == steps / 2) w.apply_impulse(0, Vec3(3.0, 1.0, -2.0), w.body(0).s.x + Vec3(0.1, 0.2, 0.0));
      w.step();
    }
    for (std::size_t k = 1; k < worlds.size(); ++k) {
      expect_identical(worlds[0], worlds[k]);
      if (::testing::Test::HasFatalFailure()) FAIL() << "at step " << i << ", thread count " << k + 1;
    }
  }
  EXPECT_GT(worlds[0].last_step().awake, 0u);
}

TEST(Threads, EveryIndexRunsOnce) {
  for (unsigned threads : {1u, 2u, 4u}) {
    WorkerPool pool(threads);
    ASSERT_EQ(pool.size(), threads);
    for (std::size_t n : {0, 1, 7, 100, 1000, 12345}) {
      std::vector<std::atomic<int>> seen(n);
      pool.for_each(n, 3, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) seen[i].fetch_add(1);
      });
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(seen[i].load(), 1) << i << " of " << n;
    }
  }
}

// for_each_phase: every index of every phase once, and a phase sees all of the one before.
// Each index of phase p adds one to the sum of three entries phase p − 1 wrote; a phase that
// began before the last finished would read a stale entry and the totals would differ.
TEST(Threads, PhasesRunInTurnAndEveryIndexOnce) {
  constexpr std::size_t kPhases = 60;
  auto size = [](std::size_t p) { return std::size_t{1 + (p * 37) % 97}; };  // 1 to 97 indices
  std::vector<std::vector<long>> expected(kPhases);
  for (std::size_t p = 0; p < kPhases; ++p) {
    expected[p].resize(size(p));
    for (std::size_t i = 0; i < size(p); ++i) {
      long before = 0;
      if (p > 0)
        for (std::size_t k = 0; k < 3; ++k)
          before += expected[p - 1][(i * 7 + k) % expected[p - 1].size()];
      expected[p][i] = before % 1000003 + 1;
    }
  }
  for (unsigned threads : {1u, 2u, 3u}) {
    WorkerPool pool(threads);
    for (int round = 0; round < 50; ++round) {
      std::vector<std::vector<long>> got(kPhases);
      for (std::size_t p = 0; p < kPhases; ++p) got[p].assign(size(p), 0);
      pool.for_each_phase(kPhases, 2, size, [&](std::size_t p, std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
          long before = 0;
          if (p > 0)
            for (std::size_t k = 0; k < 3; ++k) before += got[p - 1][(i * 7 + k) % got[p - 1].size()];
          got[p][i] += before % 1000003 + 1;  // += : an index run twice would show
          [[maybe_unused]] volatile int spin = 0;  // ~0.3 µs per index: long enough phases
          for (int k = 0; k < 300; ++k) spin = k;
        }
      });
      ASSERT_EQ(got, expected) << threads << " threads, round " << round;
    }
  }
}

// Phases of a chunk or so each (a tower's chain of contacts) have nothing to share: the
// caller runs them all, in turn, and no worker is woken for them.
TEST(Threads, PhasesOfOneChunkRunOnTheCaller) {
  WorkerPool pool(3);
  const std::thread::id caller = std::this_thread::get_id();
  std::vector<std::size_t> order;
  bool elsewhere = false;
  auto size = [](std::size_t p) { return p % 3 == 0 ? std::size_t{9} : std::size_t{4}; };  // grain 8
  pool.for_each_phase(300, 8, size, [&](std::size_t p, std::size_t begin, std::size_t end) {
    elsewhere = elsewhere || std::this_thread::get_id() != caller;
    EXPECT_EQ(begin, 0u);
    EXPECT_EQ(end, size(p));
    order.push_back(p);
  });
  EXPECT_FALSE(elsewhere);
  std::vector<std::size_t> expected(300);
  std::iota(expected.begin(), expected.end(), std::size_t{0});
  EXPECT_EQ(order, expected);
}

// The pile: 1,000 boxes falling into one another (broad phase, narrow phase, big islands
// whose contacts are solved colour by colour).
TEST(Threads, PileIsBitIdenticalOnOneTwoAndThreeThreads) {
  Scene pile = bundled("pile");
  pile.bodies.resize(testing::kPileBodies);
  expect_same_on_any_thread_count(pile, 90);
}

// The pyramid: one island of 210 boxes standing on the floor.
TEST(Threads, PyramidIsBitIdenticalOnOneTwoAndThreeThreads) {
  expect_same_on_any_thread_count(bundled("pyramid"), 30);
}

// Separated boxes: lone bodies flying with the scene's integrator and landing on the floor.
TEST(Threads, SeparatedBoxesAreBitIdenticalOnOneTwoAndThreeThreads) {
  expect_same_on_any_thread_count(bundled("many"), 240);
}

// A step whose threads were held up for more than a quarter of its time (and more than
// kLeastStall) sends the next kFirst to the caller alone; a stall soon after the probe that
// follows doubles the stretch, up to kMost; a probe that passes and stays clear for kRecent
// steps starts again from kFirst.
TEST(Threads, StepsHeldUpRunAloneForLongerStretchesWhileTheStallsGoOn) {
  using P = SoloPolicy;
  constexpr std::uint64_t kWall = 8 * P::kLeastStall, kLong = 6 * P::kLeastStall;
  P policy;
  auto alone = [&](std::uint32_t steps) {  // `steps` solo steps, then a shared one
    for (std::uint32_t i = 1; i < steps; ++i) ASSERT_TRUE(policy.next_solo(kWall, 0)) << i;
    ASSERT_FALSE(policy.next_solo(kWall, 0));
  };
  EXPECT_FALSE(policy.next_solo(kWall, kWall / 4));  // a quarter held up: still shared
  EXPECT_FALSE(policy.next_solo(P::kLeastStall, P::kLeastStall));  // a wake-up's latency
  EXPECT_FALSE(policy.next_solo(kWall, 0));
  EXPECT_TRUE(policy.next_solo(kWall, kWall / 4 + 1));
  alone(P::kFirst);
  ASSERT_TRUE(policy.next_solo(kWall, kLong));  // the probe was held up too
  alone(2 * P::kFirst);
  for (std::uint32_t n = 4 * P::kFirst; n <= P::kMost; n *= 2) {
    ASSERT_TRUE(policy.next_solo(kWall, kLong));
    alone(n);
  }
  ASSERT_TRUE(policy.next_solo(kWall, kLong));
  alone(P::kMost);  // no longer than kMost
  for (std::uint32_t i = 0; i < P::kRecent; ++i) ASSERT_FALSE(policy.next_solo(kWall, 0));
  ASSERT_TRUE(policy.next_solo(kWall, kLong));
  alone(P::kFirst);  // the cores were free for a while: the first stretch again
}

// Far cores: a round trip past the bound starts a trial of kTrialSteps alone, then as many
// shared; the first step of each side is not timed. Alone a twentieth faster than the mean of
// the fastest shared steps before and after wins kWonFirst steps alone. After them, four
// shared steps and a round trip: still far, the stretch's last steps stand against those,
// and each win doubles the stretch up to kMost. A lost trial doubles the shared steps before
// the next round trip, up to kMost; near cores never start one.
TEST(Threads, FarCoresTimeStepsAloneAgainstSharedOnesAndKeepTheFaster) {
  using P = SoloPolicy;
  constexpr std::uint64_t kShared = 3'800'000, kAlone = 3'200'000, kMoved = 9'000'000;
  constexpr std::uint64_t kNear = 60, kFar = 330;  // round trips, ns
  P policy;
  auto shared = [&](std::uint32_t steps, std::uint64_t wall) {  // returns the probes asked
    std::uint32_t probes = 0;
    for (std::uint32_t i = 0; i < steps; ++i) {
      EXPECT_FALSE(policy.next_solo(wall, 0)) << i;
      if (!policy.wants_round_trip()) continue;
      ++probes;
      EXPECT_FALSE(policy.after_round_trip(kNear));
    }
    return probes;
  };
  // Four shared steps at `wall` (ns), the first at `first`, then the round trip `rt`; returns
  // whether the next step runs alone.
  auto round_trip = [&](std::uint64_t first, std::uint64_t wall, std::uint64_t rt) {
    EXPECT_FALSE(policy.next_solo(first, 0));
    for (int i = 1; i < 4; ++i) EXPECT_FALSE(policy.next_solo(wall, 0));
    EXPECT_TRUE(policy.wants_round_trip());
    return policy.after_round_trip(rt);
  };
  // A trial once its round trip was far: its steps alone, then its shared ones (each side's
  // first at `first`); returns the verdict, whether the next step runs alone.
  auto trial = [&](std::uint64_t first, std::uint64_t alone, std::uint64_t after) {
    EXPECT_TRUE(policy.next_solo(first, 0));
    for (std::uint32_t i = 2; i < P::kTrialSteps; ++i) EXPECT_TRUE(policy.next_solo(alone, 0));
    EXPECT_FALSE(policy.next_solo(alone, 0));  // the trial's last step alone
    EXPECT_FALSE(policy.next_solo(first, 0));
    for (std::uint32_t i = 2; i < P::kTrialSteps; ++i) EXPECT_FALSE(policy.next_solo(after, 0));
    EXPECT_FALSE(policy.wants_round_trip());
    return policy.next_solo(after, 0);
  };
  auto alone = [&](std::uint32_t steps) {  // `steps` solo steps, then a shared one
    for (std::uint32_t i = 1; i < steps; ++i) ASSERT_TRUE(policy.next_solo(kAlone, 0)) << i;
    ASSERT_FALSE(policy.next_solo(kAlone, 0));
  };
  // Near cores: a round trip every kProbeEvery shared steps once three have run, no trial.
  EXPECT_EQ(shared(4 + 3 * P::kProbeEvery, kShared), 4u);
  while (!policy.wants_round_trip()) ASSERT_FALSE(policy.next_solo(kShared, 0));
  EXPECT_FALSE(policy.after_round_trip(0));  // nobody answered: not far
  EXPECT_EQ(shared(P::kProbeEvery - 4, kShared), 0u);
  // Far, the working set's moves slow and untimed: won; each recheck won doubles the stretch.
  ASSERT_TRUE(round_trip(kShared, kShared, kFar));
  ASSERT_TRUE(trial(kMoved, kAlone, kShared));
  alone(P::kWonFirst);
  for (std::uint32_t n = 2 * P::kWonFirst; n <= 2 * P::kMost; n *= 2) {
    ASSERT_TRUE(round_trip(kMoved, kShared, kFar));
    alone(std::min(n, P::kMost));
  }
  // The cores near again after a stretch: no recheck, and shared from then on.
  ASSERT_FALSE(round_trip(kMoved, 2'000'000, kNear));
  EXPECT_EQ(shared(2 * P::kProbeEvery, 2'000'000), 2u);
  // A step that grows steadily: shared 3.0 ms before the trial and 4.4 after, alone 3.2 at its
  // middle, 3.7 in the mean: won, where the steps before alone would have lost it.
  while (!policy.wants_round_trip()) ASSERT_FALSE(policy.next_solo(3'000'000, 0));
  ASSERT_TRUE(policy.after_round_trip(kFar));
  ASSERT_TRUE(trial(kMoved, kAlone, 4'400'000));
  alone(P::kWonFirst);  // a first win again: the cores were near between
  // A recheck lost: the stretch's 3.2 ms alone against 3.3 shared since.
  ASSERT_FALSE(round_trip(kMoved, 3'300'000, kFar));
  // Sharing pays though the cores stay far: alone 1.95 ms against 2.0 is not a twentieth
  // faster, though each side's first step (untimed) was fast; each loss doubles the shared
  // steps to the next round trip.
  for (std::uint32_t gap = 2 * P::kProbeEvery, losses = 0; losses < 7; ++losses) {
    std::uint32_t waited = 0;
    for (; !policy.wants_round_trip(); ++waited) ASSERT_FALSE(policy.next_solo(2'000'000, 0));
    EXPECT_EQ(waited, gap);
    ASSERT_TRUE(policy.after_round_trip(kFar));
    ASSERT_FALSE(trial(1'000'000, 1'950'000, 2'000'000));
    gap = std::min(2 * gap, P::kMost);
  }
}

// The wiring of the trials: in a pool whose every round trip counts as far, the first step
// whose round trip a worker answers starts a trial, kTrialSteps steps with every job on the
// caller, then a shared step; a pool without workers measures none. No step counts as held
// up here: on a machine busier than its cores (ctest's other jobs, a sanitizer) the stall
// count would send step after step alone, and no shared step would time a round trip.
TEST(Threads, APoolOnFarCoresRunsATrialOnTheCaller) {
  EXPECT_EQ(WorkerPool(1).round_trip_ns(), 0u);
  WorkerPool pool(2, SoloPolicy(/*far_round_trip_ns=*/1, /*least_stall_ns=*/UINT64_MAX));
  const std::thread::id caller = std::this_thread::get_id();
  auto spin = [](std::chrono::microseconds d) {
    for (auto end = std::chrono::steady_clock::now() + d; std::chrono::steady_clock::now() < end;) {
    }
  };
  // Steps past kLeastProbed, each a job the worker may join: the worker polls at their ends.
  auto step = [&] {
    const WorkerPool::Busy busy(pool);
    bool elsewhere = false;
    pool.for_each(64, 1, [&](std::size_t begin, std::size_t end) {
      spin(std::chrono::microseconds(20 * (end - begin)));
      if (std::this_thread::get_id() != caller) elsewhere = true;
    });
    return elsewhere;
  };
  // A machine busier than its cores may keep the worker off its core whenever the ball comes:
  // then no round trip is answered, and there is nothing to test.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (pool.round_trips() == 0 && std::chrono::steady_clock::now() < deadline) step();
  if (pool.round_trips() == 0) GTEST_SKIP() << "no round trip answered in 10 s";
  ASSERT_EQ(pool.round_trips(), 1u);
  for (std::uint32_t i = 0; i < SoloPolicy::kTrialSteps; ++i) {
    ASSERT_TRUE(pool.solo()) << "trial step " << i;
    EXPECT_EQ(pool.size(), 1u);
    EXPECT_FALSE(step()) << "trial step " << i << " ran a job elsewhere";
  }
  EXPECT_FALSE(pool.solo());
  // Within a step, a worker that has just run a job polls a while: it answers.
  std::uint64_t rt = 0;
  for (int i = 0; i < 1000 && rt == 0; ++i) {
    const WorkerPool::Busy busy(pool);
    pool.for_each(64, 1, [&](std::size_t, std::size_t) { spin(std::chrono::microseconds(5)); });
    rt = pool.round_trip_ns();
  }
  EXPECT_GT(rt, 0u);
  EXPECT_LT(rt, 10'000'000u);
}

// The pool's own wiring: a worker that holds a job up (asleep inside its chunk, as a
// descheduled thread would be) makes the next steps run every job on the caller, with
// size() 1, and a later step shares again.
TEST(Threads, APoolHeldUpByAWorkerRunsTheNextStepsOnTheCaller) {
  WorkerPool pool(2);
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<bool> held = false;
  // The caller's chunks spin (its own CPU time, no stall) long enough for the worker to join.
  auto spin = [](std::chrono::microseconds d) {
    for (auto end = std::chrono::steady_clock::now() + d; std::chrono::steady_clock::now() < end;) {
    }
  };
  for (int attempt = 0; attempt < 200 && !held; ++attempt) {
    const WorkerPool::Busy step(pool);
    pool.for_each_phase(2, 1, [](std::size_t) { return std::size_t{8}; },
                        [&](std::size_t, std::size_t, std::size_t) {
                          if (std::this_thread::get_id() == caller)
                            return spin(std::chrono::microseconds(200));
                          held = true;
                          std::this_thread::sleep_for(std::chrono::milliseconds(5));
                        });
  }
  ASSERT_TRUE(held) << "no worker joined a job in 200 tries";
  EXPECT_TRUE(pool.solo());
  EXPECT_EQ(pool.size(), 1u);
  EXPECT_EQ(pool.threads(), 2u);
  // kFirst steps alone, or longer where a stall of the busy machine came shortly before.
  std::uint32_t alone = 0;
  for (; pool.solo() && alone <= SoloPolicy::kMost; ++alone) {
    const WorkerPool::Busy step(pool);
    bool elsewhere = false;
    pool.for_each(10000, 1, [&](std::size_t, std::size_t) {
      elsewhere = elsewhere || std::this_thread::get_id() != caller;
    });
    EXPECT_FALSE(elsewhere) << "step " << alone;
  }
  EXPECT_GE(alone, SoloPolicy::kFirst);
  EXPECT_FALSE(pool.solo());
  EXPECT_EQ(pool.size(), 2u);
}

// What a step alone relies on: a World whose thread count changes from step to step steps
// bit for bit as one that keeps one thread.
TEST(Threads, PileIsBitIdenticalWhenItsThreadCountChangesBetweenSteps) {
  Scene pile = bundled("pile");
  pile.bodies.resize(testing::kPileBodies);
  World steady(pile), changing(pile);
  for (int i = 1; i <= 90; ++i) {
    changing.set_threads(i % 7 < 3 ? 1u : 2u);
    for (World* w : {&steady, &changing}) {
      if (i % 15 == 0)
        for (std::size_t b = 0; b < w->bodies().size(); b += 7)
          w->apply_impulse(BodyId(b), Vec3::Zero());
      w->step();
    }
    expect_identical(steady, changing);
    if (::testing::Test::HasFatalFailure()) FAIL() << "at step " << i;
  }
}

TEST(Threads, CopyKeepsTheThreadCountAndZeroMeansEveryCore) {
  World a(bundled("tower"));
  EXPECT_EQ(a.threads(), 1u);
  a.set_threads(2);
  World b = a;
  EXPECT_EQ(b.threads(), 2u);
  b.set_threads(0);
  EXPECT_EQ(b.threads(), World::hardware_threads());
}

}  // namespace
}  // namespace tumble
