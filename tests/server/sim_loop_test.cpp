#include "sim_loop.hpp"
#include "sim_pool.hpp"

#include <gtest/gtest.h>

#include <future>

#include "rest_api.hpp"
#include "tumble/scene_io.hpp"

namespace tumble::server {
namespace {

using namespace std::chrono_literals;

// The HTTP status the outcome of `kind` maps to.
unsigned run(SimLoop& sim, CommandKind kind) {
  std::promise<CommandOutcome> done;
  auto result = done.get_future();
  sim.submit({std::move(kind), [&done](CommandOutcome r) { done.set_value(std::move(r)); }});
  return outcome_status(result.get());
}

Scene scene_with_dt(double dt) {
  Scene s = load_scene("seed");
  s.world.dt = dt;
  return s;
}

TEST(SimLoop, RealTimeFactorIsOne) {
  Metrics metrics;
  SimPool pool(1);
  SimLoop sim(scene_with_dt(1.0 / 120.0), metrics);
  sim.attach(pool);
  std::this_thread::sleep_for(1500ms);
  const auto s = sim.latest();
  EXPECT_NEAR(s->real_time_factor, 1.0, 0.01);
  EXPECT_NEAR(s->time, 1.5, 0.05);
}

TEST(SimLoop, FallingBehindDropsTimeAndStaysResponsive) {
  Metrics metrics;
  SimPool pool(1);
  // 100 boxes stepped every 0.1 µs cannot be kept up with: the loop must drop time, not
  // spiral.
  Scene scene = load_scene("many");
  scene.world.dt = 1e-7;
  SimLoop sim(scene, metrics);
  sim.attach(pool);
  std::this_thread::sleep_for(1000ms);
  const auto s = sim.latest();
  EXPECT_LT(s->real_time_factor, 0.9);
  EXPECT_GT(s->real_time_factor, 0.0);
  EXPECT_LT(s->time, 0.95);
  const std::string text = metrics.render(*s, 0);
  const std::string name = "\ntumble_dropped_sim_seconds_total ";
  const auto at = text.find(name);
  ASSERT_NE(at, std::string::npos);
  EXPECT_GT(std::stod(text.substr(at + name.size())), 0.5) << text.substr(at, 60);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(run(sim, PauseCommand{}), 200u);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 200ms);
}

TEST(SimLoop, PausedItStopsAndStepsOnRequest) {
  Metrics metrics;
  SimPool pool(1);
  SimLoop sim(load_scene("seed"), metrics);
  sim.attach(pool);
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(run(sim, PauseCommand{}), 200u);
  const auto paused = sim.latest();
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(sim.latest()->step, paused->step);
  EXPECT_TRUE(sim.latest()->paused);
  EXPECT_EQ(run(sim, StepCommand{5}), 200u);
  EXPECT_EQ(sim.latest()->step, paused->step + 5);
  EXPECT_EQ(run(sim, ResumeCommand{}), 200u);
  EXPECT_EQ(run(sim, StepCommand{1}), 409u);
}

TEST(SimLoop, CommandsAfterStopGet503) {
  Metrics metrics;
  SimPool pool(1);
  SimLoop sim(load_scene("seed"), metrics);
  sim.attach(pool);
  sim.stop();
  EXPECT_EQ(run(sim, PauseCommand{}), 503u);
}

// Worlds on one pool thread: a world that can never keep up (1e-7 s steps) takes only what
// the others leave; a light world beside it stays at real time.
TEST(SimPool, AHeavyWorldSlowsOnlyItself) {
  Metrics metrics;
  SimPool pool(1);
  Scene heavy = load_scene("many");
  heavy.world.dt = 1e-7;
  SimLoop slow(heavy, metrics);
  SimLoop light(scene_with_dt(1.0 / 120.0), metrics);
  slow.attach(pool);
  light.attach(pool);
  std::this_thread::sleep_for(1500ms);
  EXPECT_LT(slow.latest()->real_time_factor, 0.9);
  EXPECT_NEAR(light.latest()->real_time_factor, 1.0, 0.02);
  EXPECT_NEAR(light.latest()->time, 1.5, 0.1);
  // A command to either still answers promptly.
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(run(light, PauseCommand{}), 200u);
  EXPECT_EQ(run(slow, PauseCommand{}), 200u);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 200ms);
}

// A stopped loop leaves the pool: the pool's thread no longer steps it, and other loops go on.
TEST(SimPool, StopTakesALoopOut) {
  Metrics metrics;
  SimPool pool(2);
  SimLoop a(load_scene("seed"), metrics);
  SimLoop b(load_scene("seed"), metrics);
  a.attach(pool);
  b.attach(pool);
  std::this_thread::sleep_for(200ms);
  a.stop();
  const auto stopped_at = a.latest()->step;
  const auto b_at = b.latest()->step;
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(a.latest()->step, stopped_at);
  EXPECT_GT(b.latest()->step, b_at);
  EXPECT_EQ(run(a, PauseCommand{}), 503u);
}

TEST(SimLoop, SnapshotsKeepThePreviousStepForInterpolation) {
  Metrics metrics;
  SimPool pool(1);
  SimLoop sim(load_scene("seed"), metrics);
  sim.attach(pool);
  std::this_thread::sleep_for(200ms);
  const auto s = sim.latest();
  ASSERT_TRUE(s->previous_bodies);
  EXPECT_NEAR(s->time - s->previous_time, 1.0 / 30.0, 1e-9);
  // Steps are taken at or just ahead of the wall clock.
  const double ahead = std::chrono::duration<double>(s->wall_time - Clock::now()).count();
  EXPECT_GT(ahead, -0.01);
  EXPECT_LT(ahead, 1.0 / 30.0 + 0.01);
}

}  // namespace
}  // namespace tumble::server
