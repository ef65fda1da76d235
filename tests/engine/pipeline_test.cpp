// The step pipeline (engine/src/pipeline.hpp): no allocation once warm, stage timings only
// when asked for, copies that continue bit for bit without the caches they do not copy.
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <new>

#include "../sanitized.hpp"
#include "world_fixture.hpp"

// ThreadSanitizer's runtime defines the global operator new itself: there the allocation
// count is not available and its test is skipped (the other builds run it).
#if defined(__SANITIZE_THREAD__)
#define TUMBLE_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define TUMBLE_TSAN 1
#endif
#endif

namespace {
// Every allocation of this test binary is counted (the count is what the test reads).
std::atomic<long> g_allocations{0};
#ifdef TUMBLE_TSAN
constexpr bool kCountsAllocations = false;
#else
constexpr bool kCountsAllocations = true;
#endif
}  // namespace

#ifndef TUMBLE_TSAN
void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#endif

namespace tumble {
namespace {

using testing::bundled;

// Box2D's and Jolt's rule: a step allocates nothing once its buffers have grown to the scene.
// The pyramid's 210 boxes keep the same contacts while they stand (kept awake by a zero
// impulse every 10 steps, which wakes their island), so after a short warm-up every buffer
// has its size and 60 further steps must not allocate at all.
TEST(Pipeline, StepAllocatesNothingOnceWarm) {
  if (!kCountsAllocations) GTEST_SKIP() << "ThreadSanitizer owns operator new in this build";
  World world(bundled("pyramid"));
  auto run = [&world](int steps) {
    for (int i = 0; i < steps; ++i) {
      if (world.step_count() % 10 == 0) world.apply_impulse(0, Vec3::Zero());
      world.step();
    }
  };
  const long at_start = g_allocations.load();
  run(20);
  ASSERT_GT(g_allocations.load() - at_start, 0);  // the counter sees the engine's buffers grow
  ASSERT_GT(world.last_step().contacts, 100u);
  const long before = g_allocations.load();
  run(60);
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(world.last_step().contacts, 100u);
}

// Throws each falling box of testing::falling_boxes up with a spin, aimed to come down on the
// base box at 12 m/s about 2.4 s later.
void throw_onto_base(World& world) {
  const double flight = 2 * 12.0 / 9.81;
  const Vec3 base = world.body(0).s.x;
  for (BodyId id = 1; id < world.bodies().size(); ++id) {
    const Body& b = world.body(id);
    const Vec3 aim(base.x() + 0.1 * id - 0.25, 0.0, base.z() + 0.05 * id);
    const Vec3 v((aim.x() - b.s.x.x()) / flight, 12.0, (aim.z() - b.s.x.z()) / flight);
    world.apply_impulse(id, b.c.mass * v - b.s.P);
    const Vec3 twist(0.5 * id, 0.0, 0.3);  // a couple: spin without a push
    world.apply_impulse(id, twist, b.s.x + Vec3(0.0, 0.3, 0.0));
    world.apply_impulse(id, -twist, b.s.x);
  }
}

// A pass taken again in halves (WorldDef::max_overlap) allocates nothing once warm: one
// snapshot serves every level of halving and grows as the contact cache it copies grew. Boxes
// are thrown onto a base box again and again, and after four throws the steps that halve must
// not allocate. (Other steps may still grow a buffer: each landing is a new draw.) Five
// snapshots, one per level, each grown only to the size it copied, allocated in such steps.
TEST(Pipeline, PassesTakenAgainAllocateNothingOnceWarm) {
  if (!kCountsAllocations) GTEST_SKIP() << "ThreadSanitizer owns operator new in this build";
  World world(testing::falling_boxes(10.0, 10.0, 0.01));
  int halving_steps = 0;
  long halving_allocations = 0;
  for (int cycle = 0; cycle < 16; ++cycle) {
    for (int i = 0; i < 240; ++i) {
      const long before = g_allocations.load();
      world.step();
      if (cycle < 4 || world.last_step().halved_passes == 0) continue;
      ++halving_steps;
      halving_allocations += g_allocations.load() - before;
    }
    throw_onto_base(world);
  }
  EXPECT_GE(halving_steps, 5);  // 13 with GCC here
  EXPECT_EQ(halving_allocations, 0);
}

TEST(Pipeline, StageTimesOnlyWhenAskedFor) {
  World world(bundled("pyramid"));
  world.step();
  for (std::uint64_t ns : world.last_step().stage_ns) EXPECT_EQ(ns, 0u);
  for (std::uint64_t ns : world.last_step().solve_pass_ns) EXPECT_EQ(ns, 0u);
  world.set_stage_timing(true);
  world.step();
  const StepStats& s = world.last_step();
  EXPECT_GT(s.stage_ns[static_cast<int>(Stage::contact_solve)], 0u);
  EXPECT_GT(s.stage_ns[static_cast<int>(Stage::narrow_phase)], 0u);
  EXPECT_STREQ(stage_name(Stage::contact_solve), "contact_solve");
}

// The contact solve's passes split its stage time: each pass that has work on a resting
// pyramid is timed, and together they fit inside the stage (the stage's own clock reads
// bracket them).
TEST(Pipeline, ContactSolvePassesSplitItsStageTime) {
  World world(bundled("pyramid"));
  world.set_stage_timing(true);
  for (int i = 0; i < 3; ++i) world.step();
  const StepStats& s = world.last_step();
  std::uint64_t sum = 0;
  for (SolvePass pass : {SolvePass::cache, SolvePass::rows, SolvePass::impacts,
                         SolvePass::warm_start, SolvePass::velocity,
                         SolvePass::shock_propagation, SolvePass::finish})
    EXPECT_GT(s.solve_pass_ns[static_cast<int>(pass)], 0u) << solve_pass_name(pass);
  for (std::uint64_t ns : s.solve_pass_ns) sum += ns;
  EXPECT_LE(sum, s.stage_ns[static_cast<int>(Stage::contact_solve)]);
  EXPECT_GT(sum, s.stage_ns[static_cast<int>(Stage::contact_solve)] / 2);
  EXPECT_STREQ(solve_pass_name(SolvePass::shock_propagation), "shock_propagation");
}

// A copy starts without the broad-phase acceleration and the scratch buffers; the results do
// not depend on them, so the copy and the original stay bit-identical.
TEST(Pipeline, CopyWithoutCachesContinuesBitForBit) {
  Scene pile = bundled("pile");
  pile.bodies.resize(testing::kPileBodies);
  World a(pile);
  for (int i = 0; i < 45; ++i) a.step();
  World b = a;
  for (int i = 0; i < 45; ++i) {
    a.step();
    b.step();
  }
  ASSERT_EQ(a.bodies().size(), b.bodies().size());
  for (std::size_t i = 0; i < a.bodies().size(); ++i)
    ASSERT_EQ(std::memcmp(&a.bodies()[i].s, &b.bodies()[i].s, sizeof(BodyState)), 0) << i;
}

// 2,000 boxes at one point would make two million pairs: the scene is refused, naming the
// field; 300 boxes of the pile as placed are well inside the budget.
TEST(Pipeline, ScenePackedBeyondThePairBudgetIsRefused) {
  Scene dense = bundled("pile");
  dense.bodies.resize(2000, dense.bodies.front());
  for (std::size_t i = 0; i < dense.bodies.size(); ++i) {
    dense.bodies[i].name = "b" + std::to_string(i);
    dense.bodies[i].position = Vec3(0.0, 5.0, 0.0);
  }
  try {
    World world(dense);
    FAIL() << "a scene of 2,000 boxes at one point was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("bodies: more than 65024 pairs"), std::string::npos)
        << e.what();
  }
  World pile(bundled("pile"));
  pile.step();
  EXPECT_EQ(pile.last_step().pair_budget_exceeded, 0u);
}

}  // namespace
}  // namespace tumble
