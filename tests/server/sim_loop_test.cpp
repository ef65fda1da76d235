#include "sim_loop.hpp"

#include <gtest/gtest.h>

#include <future>

#include "tumble/scene_io.hpp"

namespace tumble::server {
namespace {

using namespace std::chrono_literals;

CommandResult run(SimLoop& sim, CommandKind kind) {
  std::promise<CommandResult> done;
  auto result = done.get_future();
  sim.submit({std::move(kind), [&done](CommandResult r) { done.set_value(std::move(r)); }});
  return result.get();
}

Scene scene_with_dt(double dt) {
  Scene s = load_scene("seed");
  s.world.dt = dt;
  return s;
}

TEST(SimLoop, RealTimeFactorIsOne) {
  Metrics metrics;
  SimLoop sim(scene_with_dt(1.0 / 120.0), metrics);
  sim.start();
  std::this_thread::sleep_for(1500ms);
  const auto s = sim.latest();
  EXPECT_NEAR(s->real_time_factor, 1.0, 0.01);
  EXPECT_NEAR(s->time, 1.5, 0.05);
}

TEST(SimLoop, FallingBehindDropsTimeAndStaysResponsive) {
  Metrics metrics;
  // 100 boxes stepped every 0.1 µs cannot be kept up with: the loop must drop time, not
  // spiral.
  Scene scene = load_scene("many");
  scene.world.dt = 1e-7;
  SimLoop sim(scene, metrics);
  sim.start();
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
  EXPECT_EQ(run(sim, PauseCommand{}).status, 200u);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 200ms);
}

TEST(SimLoop, PausedItStopsAndStepsOnRequest) {
  Metrics metrics;
  SimLoop sim(load_scene("seed"), metrics);
  sim.start();
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(run(sim, PauseCommand{}).status, 200u);
  const auto paused = sim.latest();
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(sim.latest()->step, paused->step);
  EXPECT_TRUE(sim.latest()->paused);
  const CommandResult r = run(sim, StepCommand{5});
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(sim.latest()->step, paused->step + 5);
  EXPECT_EQ(run(sim, ResumeCommand{}).status, 200u);
  EXPECT_EQ(run(sim, StepCommand{1}).status, 409u);
}

TEST(SimLoop, CommandsAfterStopGet503) {
  Metrics metrics;
  SimLoop sim(load_scene("seed"), metrics);
  sim.start();
  sim.stop();
  EXPECT_EQ(run(sim, PauseCommand{}).status, 503u);
}

TEST(SimLoop, SnapshotsKeepThePreviousStepForInterpolation) {
  Metrics metrics;
  SimLoop sim(load_scene("seed"), metrics);
  sim.start();
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
