#include "sim_loop.hpp"

#include <cmath>
#include <cstdio>
#include <new>

#include "request_limits.hpp"
#include "sim_pool.hpp"

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

void complete(Command& command, CommandOutcome result) {
  if (!command.done) return;
  try {
    command.done(std::move(result));
  } catch (...) {
    // A completion must not throw; if one does, the simulation carries on regardless.
  }
}

}  // namespace

SimLoop::SimLoop(Scene scene, Metrics& metrics, std::chrono::milliseconds step_command_budget,
                 unsigned step_threads, TimelineLimits timeline)
    : metrics_(metrics),
      world_(std::make_unique<World>(std::move(scene))),
      timeline_(timeline),
      step_command_budget_(step_command_budget) {
  world_->set_threads(step_threads);
  loaded_bodies_ = world_->bodies().size();
  timeline_.restart(*world_, world_->scene().world.name);
  new_scene_info();
  anchor(Clock::now());
  publish(Change::restart);
}

SimLoop::~SimLoop() { stop(); }

void SimLoop::attach(SimPool& pool) {
  pool_.store(&pool);
  queue_.set_wake([this] {
    if (SimPool* p = pool_.load()) p->wake(*this);
  });
  anchor(Clock::now());
  pool.add(*this);
}

void SimLoop::stop() {
  queue_.close();
  if (stopped_.exchange(true)) return;
  if (SimPool* p = pool_.load()) p->remove(*this);
  // No pool thread runs this loop any more: answer what is left here.
  if (running_step_) finish_step("shutdown");
  for (Command& c : queue_.drain())
    complete(c, command_error(Failure::unavailable, "shutting down", ""));
}

Clock::time_point SimLoop::service() {
  for (Command& c : queue_.drain()) execute(c);
  if (running_step_) {
    continue_step();
    return Clock::now();
  }
  if (paused_) return Clock::time_point::max();  // Only a command brings work; no CPU used.
  try {
    advance();
  } catch (const std::exception& e) {  // std::bad_alloc above all: the process lives on.
    on_step_failure(e);
    return Clock::time_point::max();
  }
  // Due when the wall clock reaches the sim time just computed.
  return anchor_wall_ + std::chrono::duration_cast<Clock::duration>(
                            std::chrono::duration<double>((world_->time() - anchor_sim_) / speed_));
}

// An allocation failure inside a step leaves the world as that step left it (World::step is
// not transactional, and a copy of the last good world would cost a World copy per step):
// the loop pauses (so the failure is not retried every step), publishes that world as
// paused, logs once and counts it; POST /api/resume tries again, POST /api/reset starts
// afresh. If even the snapshot cannot be allocated, the previous one stays published.
void SimLoop::on_step_failure(const std::exception& e) {
  metrics_.count_step_failure();
  std::fprintf(stderr, "tumble-server: simulation step failed: %s (paused)\n", e.what());
  paused_ = true;
  try {
    publish(Change::command);
  } catch (const std::exception&) {
  }
}

void SimLoop::world_step() {
  if (before_step_) before_step_();
  world_->step();
  after_step();
}

bool SimLoop::at_past() const {
  return timeline_.enabled() && world_->step_count() < timeline_.head().step;
}

// A step at a past step replays the recorded future (its logged commands apply at their
// steps); reaching the newest recorded step, a playback goes on live at 1×. A step beyond it
// is recorded.
void SimLoop::after_step() {
  if (!timeline_.enabled() || world_->step_count() > timeline_.head().step)
    return timeline_.record_step(*world_);
  timeline_.apply_logged_at(*world_);
  if (world_->step_count() == timeline_.head().step && playing_) {
    playing_ = false;
    speed_ = 1.0;
    anchor(Clock::now());
  }
}

// A command that changes the world at a past step discards the recorded future first.
void SimLoop::log_command(LoggedCommand command) {
  timeline_.record_command(*world_, std::move(command));
}

void SimLoop::anchor(Clock::time_point now) {
  anchor_wall_ = now;
  anchor_sim_ = world_->time();
  rtf_samples_.clear();
}

double SimLoop::sim_clock(Clock::time_point now) const {
  return anchor_sim_ + speed_ * seconds(now - anchor_wall_);
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
  world_step();
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
  // Bodies added (or, after a seek or a playback, fewer or more of them): a new scene for the
  // viewers, and no interpolation across the change.
  if (world_->bodies().size() != scene_info_->constants.size()) {
    new_scene_info();
    change = Change::restart;
  }
  auto s = std::make_shared<Snapshot>();
  s->scene = scene_info_;
  s->time = world_->time();
  s->step = world_->step_count();
  s->paused = paused_;
  s->speed = speed_;
  s->live = !at_past();
  s->playing = playing_;
  s->history_bytes = timeline_.bytes();
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
                                    std::chrono::duration<double>((s->time - anchor_sim_) / speed_));
  if (contact_subscribers_.load(std::memory_order_relaxed) > 0) {
    world_->contacts(contact_scratch_);
    auto set = std::make_shared<ContactSet>();
    set->step = s->step;
    set->truncated = contact_scratch_.size() > ContactSet::kMaxPoints;
    set->points.assign(contact_scratch_.begin(),
                       contact_scratch_.begin() + static_cast<std::ptrdiff_t>(std::min(
                                                      contact_scratch_.size(), ContactSet::kMaxPoints)));
    s->contacts = std::move(set);
  }
  latest_.store(std::move(s));
}

void SimLoop::execute(Command& command) {
  const bool is_step = std::holds_alternative<StepCommand>(command.kind);
  if (running_step_) {
    if (is_step)
      return complete(command,
                      command_error(Failure::conflict, "a step is already running", "steps"));
    // Pause, resume, reset, seek and play cancel the running step; impulses, integrator
    // changes, speed changes and reads apply between its chunks.
    if (!std::holds_alternative<ImpulseCommand>(command.kind) &&
        !std::holds_alternative<SetIntegratorCommand>(command.kind) &&
        !std::holds_alternative<AddBodyCommand>(command.kind) &&
        !std::holds_alternative<SpeedCommand>(command.kind) &&
        !std::holds_alternative<HistoryCommand>(command.kind) &&
        !std::holds_alternative<RecordingCommand>(command.kind))
      finish_step("cancelled");
  }
  if (is_step) return start_step(command);
  CommandOutcome result;
  try {
    result = run_command(command.kind);
  } catch (const InvalidInput& e) {
    result = command_error(Failure::invalid, e.what(), "");
  } catch (const std::bad_alloc&) {
    metrics_.count_step_failure();
    result = command_error(Failure::unavailable, "out of memory: the command was not applied", "");
  } catch (const std::exception& e) {
    result = command_error(Failure::internal, e.what(), "");
  }
  complete(command, std::move(result));
}

CommandOutcome SimLoop::run_command(CommandKind& kind) {
  if (auto* c = std::get_if<ResetCommand>(&kind)) return reset(*c);
  if (auto* c = std::get_if<ImpulseCommand>(&kind)) return impulse(*c);
  if (auto* c = std::get_if<SetIntegratorCommand>(&kind)) {
    if (at_past()) timeline_.discard_future(*world_);
    LoggedCommand logged;
    logged.kind = LoggedKind::integrator;
    logged.integrator = c->integrator;
    apply_logged(*world_, logged);
    log_command(std::move(logged));
    publish(Change::command);
    return IntegratorSet{c->integrator};
  }
  if (auto* c = std::get_if<AddBodyCommand>(&kind)) return add_body(*c);
  if (auto* c = std::get_if<SeekCommand>(&kind)) return seek(*c);
  if (auto* c = std::get_if<PlayCommand>(&kind)) return play(*c);
  if (auto* c = std::get_if<SpeedCommand>(&kind)) {
    speed_ = c->speed;
    anchor(Clock::now());
    publish(Change::command);
    return play_state();
  }
  if (std::holds_alternative<HistoryCommand>(kind)) return history();
  if (std::holds_alternative<RecordingCommand>(kind)) return recording();
  return pause_or_resume(std::holds_alternative<PauseCommand>(kind));
}

// Pause at a past step stops a playback and keeps the recorded future; resume there discards
// it and goes on live ("resume from here"). Live, each change of state is logged.
CommandOutcome SimLoop::pause_or_resume(bool pause) {
  if (pause && playing_) {
    playing_ = false;
    paused_ = true;
    publish(Change::command);
    return PausedState{paused_};
  }
  if (!pause && at_past()) {
    timeline_.discard_future(*world_);
    playing_ = false;
    paused_ = true;  // Logged below as a change to running.
  }
  if (pause != paused_) {
    paused_ = pause;
    LoggedCommand logged;
    logged.kind = pause ? LoggedKind::pause : LoggedKind::resume;
    log_command(std::move(logged));
    if (!paused_) anchor(Clock::now());
    publish(Change::command);
  }
  return PausedState{paused_};
}

CommandOutcome SimLoop::seek(const SeekCommand& c) {
  if (!timeline_.enabled())
    return command_error(Failure::conflict,
                         "this world keeps no history (--history-s 0, or a checkpoint would not "
                         "fit --history-mb)",
                         "");
  const TimelinePoint from = timeline_.from();
  const TimelinePoint to = timeline_.head();
  const std::string range = "the history holds steps " + std::to_string(from.step) + ".." +
                            std::to_string(to.step) + " (time " + std::to_string(from.time) +
                            ".." + std::to_string(to.time) + " s)";
  std::optional<std::uint64_t> step = c.step;
  if (c.time) {
    step = timeline_.step_at(*c.time, world_->settings().dt);
    if (!step) return command_error(Failure::invalid, "time out of range: " + range, "time");
  }
  std::optional<World> world = timeline_.restore(*step);
  if (!world)
    return command_error(Failure::invalid, "step out of range: " + range, c.time ? "time" : "step");
  world_ = std::make_unique<World>(std::move(*world));
  paused_ = true;
  playing_ = false;
  publish(Change::restart);
  return SeekDone{world_->time(), world_->step_count()};
}

CommandOutcome SimLoop::play(const PlayCommand& c) {
  if (at_past()) {
    playing_ = true;
    paused_ = false;
    speed_ = c.speed;
    anchor(Clock::now());
    publish(Change::command);
    return play_state();
  }
  speed_ = c.speed;
  pause_or_resume(false);
  anchor(Clock::now());
  publish(Change::command);
  return play_state();
}

PlayState SimLoop::play_state() const {
  return {world_->time(), world_->step_count(), playing_, paused_, speed_};
}

CommandOutcome SimLoop::history() const {
  HistoryReport r;
  r.timeline = timeline_.summary();
  r.at = {world_->step_count(), world_->time()};
  r.live = !at_past();
  r.playing = playing_;
  r.paused = paused_;
  r.speed = speed_;
  r.bytes_limit = timeline_.bytes_limit();
  r.history_s = timeline_.history_s();
  return r;
}

CommandOutcome SimLoop::recording() const {
  if (!timeline_.enabled())
    return command_error(Failure::conflict,
                         "this world keeps no history (--history-s 0, or a checkpoint would not "
                         "fit --history-mb), so no recording",
                         "");
  std::optional<Recording> r = timeline_.recording(*world_);
  if (!r)
    return command_error(Failure::conflict,
                         "the command log no longer reaches back to step 0 (--history-mb), or "
                         "holds more than " + std::to_string(kMaxRecordingCommands) +
                             " commands; a reset starts a new recording",
                         "");
  return RecordingReport{std::make_shared<const Recording>(std::move(*r))};
}

CommandOutcome SimLoop::reset(ResetCommand& c) {
  Scene scene = c.scene ? std::move(*c.scene) : world_->scene();
  if (!c.scene) scene.bodies.resize(std::min(scene.bodies.size(), loaded_bodies_));  // As loaded.
  std::unique_ptr<World> world;
  try {
    world = std::make_unique<World>(std::move(scene));
    world->set_threads(world_->threads());
  } catch (const InvalidInput& e) {
    // The engine names the field first ("bodies: more than 65024 pairs …"): no change here.
    const std::string what = e.what();
    const std::size_t colon = what.find(": ");
    return command_error(Failure::invalid, what,
                         colon == std::string::npos ? "scene" : "scene." + what.substr(0, colon));
  }
  world_ = std::move(world);
  loaded_bodies_ = world_->bodies().size();
  playing_ = false;
  timeline_.restart(*world_, world_->scene().world.name);
  new_scene_info();
  anchor(Clock::now());
  publish(Change::restart);
  return SceneReset{world_->scene().world.name};
}

void SimLoop::start_step(Command& command) {
  if (!paused_)
    return complete(command, command_error(Failure::conflict, "step is only allowed while paused",
                                           "steps"));
  const std::uint32_t steps = std::get<StepCommand>(command.kind).steps;
  running_step_.emplace(
      RunningStep{std::move(command), steps, 0, Clock::now() + step_command_budget_});
}

// One chunk of the running step: at most kStepBudget of wall time, then back to the queue.
void SimLoop::continue_step() {
  RunningStep& r = *running_step_;
  const Clock::time_point chunk_end = std::min(Clock::now() + kStepBudget, r.deadline);
  try {
    while (r.done < r.requested) {
      const Clock::time_point t0 = Clock::now();
      if (t0 >= chunk_end) break;
      world_step();
      metrics_.observe_step(seconds(Clock::now() - t0));
      ++r.done;
    }
  } catch (const std::exception& e) {
    metrics_.count_step_failure();
    std::fprintf(stderr, "tumble-server: step command failed: %s\n", e.what());
    return finish_step("out of memory");
  }
  if (r.done == r.requested) return finish_step(nullptr);
  if (Clock::now() >= r.deadline) return finish_step("budget");
  publish(Change::restart);  // Viewers see the progress of a long step.
}

// Answers the running step: complete, or stopped early ("budget", "cancelled", "shutdown",
// "out of memory") with the steps actually taken. Either way the world is as stepped.
void SimLoop::finish_step(const char* stopped) {
  RunningStep r = std::move(*running_step_);
  running_step_.reset();
  CommandOutcome result;
  try {
    publish(Change::restart);
    result = StepReport{world_->time(), world_->step_count(), r.requested, r.done, stopped};
  } catch (const std::exception&) {
    result = command_error(Failure::unavailable, "out of memory", "");
  }
  complete(r.command, std::move(result));
}

CommandOutcome SimLoop::impulse(const ImpulseCommand& c) {
  BodyId id = 0;
  if (const auto* index = std::get_if<BodyId>(&c.body)) {
    if (*index >= world_->bodies().size())
      return command_error(Failure::not_found, "no body with index " + std::to_string(*index),
                           "body");
    id = *index;
  } else if (!world_->find_body(std::get<std::string>(c.body), id)) {
    return command_error(Failure::not_found,
                         "no body named '" + quoted_prefix(std::get<std::string>(c.body)) + "'",
                         "body");
  }
  // Bounded in total, not only per kick: the body's speed and spin after this impulse.
  const Body& b = world_->bodies()[id];
  const Vec3 arm = c.point ? Vec3(*c.point - b.s.x) : Vec3(Vec3::Zero());
  BodyState after = b.s;
  after.P += c.impulse;
  after.L += arm.cross(c.impulse);
  const double speed = velocity(after, b.c).norm();
  const double spin = angular_velocity(after, b.c).norm();
  if (speed > kMaxSpeed && speed > velocity(b.s, b.c).norm())
    return command_error(Failure::invalid, "the impulse would give the body a speed over 1000 m/s",
                         "impulse");
  if (spin > kMaxSpin && spin > angular_velocity(b.s, b.c).norm())
    return command_error(Failure::invalid, "the impulse would give the body a spin over 1000 rad/s",
                         "impulse");
  if (at_past()) timeline_.discard_future(*world_);
  LoggedCommand logged;
  logged.kind = LoggedKind::impulse;
  logged.body = id;
  logged.impulse = c.impulse;
  logged.point = c.point;
  apply_logged(*world_, logged);
  log_command(std::move(logged));
  publish(Change::command);
  return ImpulseApplied{};
}

// A body added at a past step discards the recorded future first, like an impulse. Its name
// is the given one, or "box-<n>" with the first n (from the body count) no body has.
CommandOutcome SimLoop::add_body(AddBodyCommand& c) {
  if (world_->bodies().size() >= c.max_bodies)
    return command_error(Failure::conflict,
                         "the world has " + std::to_string(world_->bodies().size()) +
                             " bodies; this server takes at most " +
                             std::to_string(c.max_bodies) + " per world (--max-bodies)",
                         "bodies");
  BodyDef& def = c.definition;
  BodyId existing = 0;
  if (!c.named) {
    for (std::size_t n = world_->bodies().size();; ++n) {
      def.name = "box-" + std::to_string(n);
      if (!world_->find_body(def.name, existing)) break;
    }
  } else if (world_->find_body(def.name, existing)) {
    return command_error(Failure::invalid,
                         "name: a body named '" + quoted_prefix(def.name) + "' exists already",
                         "name");
  }
  if (at_past()) timeline_.discard_future(*world_);
  LoggedCommand logged;
  logged.kind = LoggedKind::add_body;
  logged.body = static_cast<BodyId>(world_->bodies().size());
  logged.definition = std::make_shared<const BodyDef>(def);
  try {
    apply_logged(*world_, logged);
  } catch (const InvalidInput& e) {
    // "bodies[12].mass: …": the request's field is "mass".
    std::string what = e.what();
    std::string field;
    const std::size_t colon = what.find(": ");
    const std::size_t dot = what.find("].");
    if (colon != std::string::npos && dot != std::string::npos && dot < colon)
      field = what.substr(dot + 2, colon - dot - 2);
    if (dot != std::string::npos && dot < colon) what = what.substr(dot + 2);
    return command_error(Failure::invalid, what, field);
  }
  const BodyAdded added{logged.body, def.name};
  log_command(std::move(logged));
  publish(Change::command);
  return added;
}

}  // namespace tumble::server
