#include "sim_loop.hpp"

#include <cmath>

namespace tumble::server {
namespace {

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::shared_ptr<const std::vector<BodyPose>> poses_of(const World& world) {
  auto poses = std::make_shared<std::vector<BodyPose>>();
  poses->reserve(world.bodies().size());
  for (const Body& b : world.bodies())
    poses->push_back({b.s.x, b.s.R, velocity(b.s, b.c), angular_velocity(b.s, b.c), b.activity});
  return poses;
}

void complete(Command& command, CommandResult result) {
  if (!command.done) return;
  try {
    command.done(std::move(result));
  } catch (...) {
    // A completion must not throw; if one does, the simulation carries on regardless.
  }
}

}  // namespace

SimLoop::SimLoop(Scene scene, Metrics& metrics)
    : metrics_(metrics), world_(std::make_unique<World>(std::move(scene))) {
  new_scene_info();
  anchor(Clock::now());
  publish(Change::restart);
}

SimLoop::~SimLoop() { stop(); }

void SimLoop::start() {
  if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
}

void SimLoop::stop() {
  queue_.close();
  if (thread_.joinable()) thread_.join();
}

void SimLoop::run() {
  anchor(Clock::now());
  while (true) {
    for (Command& c : queue_.drain()) execute(c);
    if (queue_.closed()) break;
    if (paused_) {
      queue_.wait();  // Paused: sleep until a command arrives; no CPU is used.
      continue;
    }
    advance();
    // Sleep until the wall clock reaches the sim time just computed, or a command arrives.
    queue_.wait_until(anchor_wall_ + std::chrono::duration_cast<Clock::duration>(
                                         std::chrono::duration<double>(
                                             world_->time() - anchor_sim_)));
  }
  for (Command& c : queue_.drain()) complete(c, command_error(503, "shutting down", ""));
}

void SimLoop::anchor(Clock::time_point now) {
  anchor_wall_ = now;
  anchor_sim_ = world_->time();
  rtf_samples_.clear();
}

double SimLoop::sim_clock(Clock::time_point now) const {
  return anchor_sim_ + seconds(now - anchor_wall_);
}

// Fixed-step real-time loop (the accumulator is sim_clock(now) − world time): steps are
// taken until the world is at or just ahead of the real-time clock, so a frame can always
// interpolate between the last two steps at its own time. Behind by more than kMaxCatchUp,
// the excess is dropped (the clock is re-anchored) and the real-time factor shows it.
void SimLoop::advance() {
  const Clock::time_point now = Clock::now();
  const double dt = world_->settings().dt;
  const double behind = sim_clock(now) - world_->time();
  if (behind > kMaxCatchUp) {
    const double dropped = behind - dt;
    anchor_sim_ -= dropped;
    metrics_.add_dropped_time(dropped);
  }
  // Commands must not wait behind a long catch-up: past the budget, return to the queue (the
  // next call drops what is still owed beyond kMaxCatchUp).
  const Clock::time_point budget_end = now + kStepBudget;
  while (sim_clock(now) > world_->time() && Clock::now() < budget_end) step_once();
}

// The real-time factor compares, over the last kRtfWindow seconds, the sim time at which
// steps started with the wall time at which they started.
void SimLoop::step_once() {
  const Clock::time_point t0 = Clock::now();
  if (rtf_samples_.empty() || t0 - rtf_samples_.back().first >= std::chrono::milliseconds(1))
    rtf_samples_.emplace_back(t0, world_->time());
  while (rtf_samples_.size() > 2 && seconds(t0 - rtf_samples_[1].first) >= kRtfWindow)
    rtf_samples_.pop_front();
  const double wall = seconds(t0 - rtf_samples_.front().first);
  if (wall >= kRtfMinWindow)
    real_time_factor_ = (world_->time() - rtf_samples_.front().second) / wall;
  world_->step();
  metrics_.observe_step(seconds(Clock::now() - t0));
  publish(Change::step);
}

void SimLoop::new_scene_info() {
  std::vector<BodyConstants> constants;
  constants.reserve(world_->bodies().size());
  for (const Body& b : world_->bodies()) constants.push_back(b.c);
  scene_info_ = make_scene_info(++generation_, world_->scene(), std::move(constants));
}

void SimLoop::publish(Change change) {
  auto s = std::make_shared<Snapshot>();
  s->scene = scene_info_;
  s->time = world_->time();
  s->step = world_->step_count();
  s->paused = paused_;
  s->real_time_factor = paused_ ? 0.0 : real_time_factor_;
  s->energy = world_->total_energy();
  s->integrator = world_->settings().integrator;
  s->awake = world_->awake_count();
  s->frozen = world_->frozen_count();
  s->bodies = poses_of(*world_);
  const std::shared_ptr<const Snapshot> last = latest_.load();
  if (last && change == Change::step) {
    s->previous_bodies = last->bodies;
    s->previous_time = last->time;
  } else if (last && change == Change::command) {
    s->previous_bodies = last->previous_bodies;
    s->previous_time = last->previous_time;
  }
  s->wall_time = anchor_wall_ + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(s->time - anchor_sim_));
  latest_.store(std::move(s));
}

void SimLoop::execute(Command& command) {
  CommandResult result;
  try {
    result = run_command(command.kind);
  } catch (const InvalidInput& e) {
    result = command_error(400, e.what(), "");
  } catch (const std::exception& e) {
    result = command_error(500, e.what(), "");
  }
  complete(command, std::move(result));
}

CommandResult SimLoop::run_command(CommandKind& kind) {
  if (auto* c = std::get_if<ResetCommand>(&kind)) return reset(*c);
  if (auto* c = std::get_if<StepCommand>(&kind)) return step_paused(*c);
  if (auto* c = std::get_if<ImpulseCommand>(&kind)) return impulse(*c);
  if (auto* c = std::get_if<SetIntegratorCommand>(&kind)) {
    world_->set_integrator(c->integrator);
    publish(Change::command);
    return {200, {{"ok", true}, {"integrator", std::string(to_string(c->integrator))}}};
  }
  const bool pause = std::holds_alternative<PauseCommand>(kind);
  if (pause != paused_) {
    paused_ = pause;
    if (!paused_) anchor(Clock::now());
    publish(Change::command);
  }
  return {200, {{"ok", true}, {"paused", paused_}}};
}

CommandResult SimLoop::reset(ResetCommand& c) {
  Scene scene = c.scene ? std::move(*c.scene) : world_->scene();
  auto world = std::make_unique<World>(std::move(scene));  // May throw InvalidInput: no change.
  world_ = std::move(world);
  new_scene_info();
  anchor(Clock::now());
  publish(Change::restart);
  return {200, {{"ok", true}, {"scene", world_->scene().world.name}}};
}

CommandResult SimLoop::step_paused(const StepCommand& c) {
  if (!paused_) return command_error(409, "step is only allowed while paused", "steps");
  for (std::uint32_t i = 0; i < c.steps; ++i) {
    if (i % 64 == 63 && queue_.closed()) break;  // Shutting down: don't hold it up.
    const Clock::time_point t0 = Clock::now();
    world_->step();
    metrics_.observe_step(seconds(Clock::now() - t0));
  }
  publish(Change::restart);
  return {200, {{"ok", true}, {"time", world_->time()}, {"step", world_->step_count()}}};
}

CommandResult SimLoop::impulse(const ImpulseCommand& c) {
  BodyId id = 0;
  if (const auto* index = std::get_if<BodyId>(&c.body)) {
    if (*index >= world_->bodies().size())
      return command_error(404, "no body with index " + std::to_string(*index), "body");
    id = *index;
  } else if (!world_->find_body(std::get<std::string>(c.body), id)) {
    return command_error(404, "no body named '" + std::get<std::string>(c.body) + "'", "body");
  }
  if (c.point)
    world_->apply_impulse(id, c.impulse, *c.point);
  else
    world_->apply_impulse(id, c.impulse);
  publish(Change::command);
  return {200, {{"ok", true}}};
}

}  // namespace tumble::server
