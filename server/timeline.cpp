#include "timeline.hpp"

#include <algorithm>
#include <cmath>

namespace tumble::server {

namespace {

/// Bytes of one contact of the engine's cache (8 points of warm-start data and its key): an
/// estimate from engine/src/contact_solver.hpp, which the server cannot include.
constexpr std::size_t kContactBytes = 1232;
/// Bookkeeping of a deque element beyond its own size (allocator, block map).
constexpr std::size_t kEntryOverhead = 16;

}  // namespace

std::size_t estimate_world_bytes(const World& world) {
  std::size_t bytes = sizeof(World) + sizeof(Scene);
  std::size_t touching = 0;
  for (const Body& b : world.bodies()) {
    bytes += sizeof(Body) + sizeof(std::uint32_t);  // The body and its sleep ring entry.
    touching += b.in_contact ? 1 : 0;
  }
  for (const BodyDef& d : world.scene().bodies)
    bytes += sizeof(BodyDef) + (d.name.size() > 15 ? d.name.capacity() + 1 : 0) +
             (d.color.size() > 15 ? d.color.capacity() + 1 : 0);
  bytes += (touching + world.last_step().contacts) * kContactBytes;
  return bytes;
}

Timeline::Timeline(TimelineLimits limits) : limits_(limits) {}

void Timeline::restart(const World& world, const std::string& scene_name) {
  checkpoints_.clear();
  checkpoint_bytes_ = 0;
  log_.clear();
  impacts_.clear();
  impacts_last_step_ = false;
  scene_ = world.scene();
  origin_kept_ = world.step_count() == 0;
  head_ = {world.step_count(), world.time()};
  base_interval_ = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::llround(kBaseInterval / world.settings().dt)));
  interval_ = base_interval_;
  // Two checkpoints must fit in a quarter of the bound, or seeking would mean re-simulating
  // the whole history: such a world keeps no timeline.
  enabled_ = limits_.history_s > 0.0 && estimate_world_bytes(world) * 8 <= limits_.bytes_limit;
  if (!enabled_) return;
  take_checkpoint(world);
  LoggedCommand reset;
  reset.kind = LoggedKind::reset;
  reset.scene = scene_name;
  record_command(world, std::move(reset));
}

TimelinePoint Timeline::from() const {
  return checkpoints_.empty() ? head_ : checkpoints_.front().at;
}

void Timeline::take_checkpoint(const World& world) {
  const std::size_t bytes = estimate_world_bytes(world);
  checkpoints_.push_back({{world.step_count(), world.time()}, world, bytes});
  checkpoint_bytes_ += bytes;
}

void Timeline::record_step(const World& world) {
  if (!enabled_) return;
  head_ = {world.step_count(), world.time()};
  const std::uint32_t impacts = world.last_step().impacts;
  if (impacts > 0 && !impacts_last_step_) {
    impacts_.push_back({head_.step, head_.time, impacts});
    if (impacts_.size() > kMaxImpacts) impacts_.pop_front();
  }
  impacts_last_step_ = impacts > 0;
  if (checkpoints_.empty() || head_.step % interval_ == 0) take_checkpoint(world);
  trim();
}

void Timeline::record_command(const World& world, LoggedCommand command) {
  if (!enabled_) return;
  command.step = world.step_count();
  command.time = world.time();
  log_.push_back(std::move(command));
  trim();
}

void Timeline::discard_future(const World& world) {
  if (!enabled_) return;
  const std::uint64_t k = world.step_count();
  while (!log_.empty() && log_.back().step > k) log_.pop_back();
  while (!checkpoints_.empty() && checkpoints_.back().at.step > k) {
    checkpoint_bytes_ -= checkpoints_.back().bytes;
    checkpoints_.pop_back();
  }
  while (!impacts_.empty() && impacts_.back().step > k) impacts_.pop_back();
  impacts_last_step_ = world.last_step().impacts > 0;
  head_ = {k, world.time()};
}

void Timeline::apply_logged_at(World& world) const {
  const std::uint64_t k = world.step_count();
  auto it = std::lower_bound(log_.begin(), log_.end(), k,
                             [](const LoggedCommand& c, std::uint64_t s) { return c.step < s; });
  for (; it != log_.end() && it->step == k; ++it) apply_logged(world, *it);
}

std::optional<World> Timeline::restore(std::uint64_t step) const {
  if (!enabled_ || checkpoints_.empty() || step < checkpoints_.front().at.step ||
      step > head_.step)
    return std::nullopt;
  // The last checkpoint at or before `step`: checkpoints are taken after a step and before
  // the commands of that step, so its commands are applied first.
  auto it = std::upper_bound(
      checkpoints_.begin(), checkpoints_.end(), step,
      [](std::uint64_t s, const Checkpoint& c) { return s < c.at.step; });
  std::optional<World> world(std::prev(it)->world);
  for (;;) {
    apply_logged_at(*world);
    if (world->step_count() >= step) break;
    world->step();
  }
  return world;
}

std::optional<std::uint64_t> Timeline::step_at(double time, double dt) const {
  const TimelinePoint lo = from();
  if (!enabled_ || !(time >= lo.time - dt / 2) || !(time <= head_.time + dt / 2))
    return std::nullopt;
  const double steps = std::round((time - lo.time) / dt);
  const std::uint64_t k = lo.step + static_cast<std::uint64_t>(std::max(0.0, steps));
  return std::min(k, head_.step);
}

TimelineSummary Timeline::summary() const {
  TimelineSummary s;
  s.enabled = enabled_;
  s.from = from();
  s.to = head_;
  s.checkpoints = checkpoints_.size();
  s.interval = interval_;
  s.bytes = bytes();
  for (auto it = log_.rbegin(); it != log_.rend() && it->step >= s.from.step; ++it) {
    if (s.commands.size() == kMaxListed) {
      s.commands_truncated = true;
      break;
    }
    s.commands.push_back(*it);
  }
  std::reverse(s.commands.begin(), s.commands.end());
  for (auto it = impacts_.rbegin();
       it != impacts_.rend() && it->step >= s.from.step && s.impacts.size() < kMaxListed; ++it)
    s.impacts.push_back(*it);
  std::reverse(s.impacts.begin(), s.impacts.end());
  return s;
}

std::optional<Recording> Timeline::recording(const World& world) const {
  if (!enabled_ || !origin_kept_) return std::nullopt;
  Recording r;
  r.scene = scene_;
  for (const LoggedCommand& c : log_) {
    if (c.step > world.step_count()) break;
    if (r.commands.size() == kMaxRecordingCommands) return std::nullopt;
    r.commands.push_back(c);
  }
  r.final_step = world.step_count();
  r.final_time = world.time();
  r.digest = state_digest(world);
  return r;
}

std::size_t Timeline::log_bytes() const {
  return log_.size() * (sizeof(LoggedCommand) + kEntryOverhead);
}

std::size_t Timeline::marker_bytes() const {
  return impacts_.size() * (sizeof(ImpactMarker) + kEntryOverhead);
}

void Timeline::drop_oldest_checkpoint() {
  checkpoint_bytes_ -= checkpoints_.front().bytes;
  checkpoints_.pop_front();
  const std::uint64_t oldest = from().step;
  while (!impacts_.empty() && impacts_.front().step < oldest) impacts_.pop_front();
}

// Halves the checkpoints: the interval doubles and only those on the new grid stay (the
// oldest always, so the range does not shrink). Seeking then re-simulates up to twice as
// many steps.
void Timeline::thin() {
  interval_ *= 2;
  std::deque<Checkpoint> kept;
  for (std::size_t i = 0; i < checkpoints_.size(); ++i) {
    if (i == 0 || checkpoints_[i].at.step % interval_ == 0)
      kept.push_back(std::move(checkpoints_[i]));
    else
      checkpoint_bytes_ -= checkpoints_[i].bytes;
  }
  checkpoints_ = std::move(kept);
}

// The window first (--history-s of sim time behind the head, from the checkpoint at or before
// its start); then the byte bound: the log's part before the window (kept only for
// recordings), then thinning, then the oldest checkpoints. A log that alone overflows the
// bound (a flood of commands) restarts the history at the next step.
void Timeline::trim() {
  const double cutoff = head_.time - limits_.history_s;
  while (checkpoints_.size() >= 2 && checkpoints_[1].at.time <= cutoff) drop_oldest_checkpoint();
  while (bytes() > limits_.bytes_limit) {
    const std::uint64_t oldest = from().step;
    if (!log_.empty() && log_.front().step < oldest) {
      while (!log_.empty() && log_.front().step < oldest) log_.pop_front();
      origin_kept_ = false;
    } else if (checkpoints_.size() > 4) {
      thin();
    } else if (checkpoints_.size() >= 2) {
      drop_oldest_checkpoint();
    } else {
      checkpoints_.clear();
      checkpoint_bytes_ = 0;
      log_.clear();
      impacts_.clear();
      origin_kept_ = false;
      break;
    }
  }
}

}  // namespace tumble::server
