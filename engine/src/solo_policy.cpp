#include "solo_policy.hpp"

#include <algorithm>
#include <utility>

namespace tumble {
namespace {

std::uint64_t fastest(const std::array<std::uint64_t, 3>& walls) {
  return *std::min_element(walls.begin(), walls.end());
}

}  // namespace

bool SoloPolicy::next_solo(std::uint64_t wall_ns, std::uint64_t stalled_ns) {
  if (trial_left_ > 0) return trial_step(wall_ns);
  if (left_ > 0) {  // a step alone; after the last one, a shared step tries the cores again
    if (won_stretch_) alone_[left_ % alone_.size()] = wall_ns;
    if (--left_ == 0) {
      since_ = 0, shared_ = 0;
      recheck_ = std::exchange(won_stretch_, false);
    }
    return left_ > 0;
  }
  if (4 * stalled_ns > wall_ns && stalled_ns > least_stall_ns_) {
    length_ = since_ < kRecent ? std::min(2 * length_, kMost) : kFirst;
    left_ = length_;
    after_left_ = 0;  // a trial's shared steps, or those after a won stretch, held up: no verdict
    recheck_ = false;
    return true;
  }
  since_ = std::min(since_ + 1, kRecent);
  recent_[shared_ % recent_.size()] = wall_ns;
  shared_ = std::min(shared_ + 1, kMost);
  if (until_probe_ > 0) --until_probe_;
  if (after_left_ > 0 && --after_left_ == 0)
    return verdict(before_best_, fastest(recent_), trial_best_);
  return false;
}

// The first shared step after steps alone brings the working set back; it is out of recent_
// once three more have run.
bool SoloPolicy::wants_round_trip() const {
  return left_ == 0 && trial_left_ == 0 && after_left_ == 0 && until_probe_ == 0 &&
         shared_ > recent_.size();
}

// After a won stretch the cores need no trial of their own: its last steps alone stand
// against the shared ones since. A step whose cost grows then favours the steps alone a
// little; the next recheck, or a trial once the cores are near again, corrects that.
bool SoloPolicy::after_round_trip(std::uint64_t round_trip_ns) {
  until_probe_ = gap_;
  const bool recheck = std::exchange(recheck_, false);
  if (round_trip_ns == 0 || round_trip_ns < far_round_trip_ns_) {
    won_ = 0;
    return false;
  }
  if (recheck) return verdict(fastest(recent_), fastest(recent_), fastest(alone_));
  trial_left_ = kTrialSteps;
  trial_best_ = UINT64_MAX;
  before_best_ = fastest(recent_);
  return true;
}

bool SoloPolicy::trial_step(std::uint64_t wall_ns) {
  if (trial_left_ < kTrialSteps) trial_best_ = std::min(trial_best_, wall_ns);
  if (--trial_left_ > 0) return true;
  shared_ = 0;
  after_left_ = kTrialSteps;  // the first brings the working set back, then recent_ fills
  return false;
}

// Alone against the mean of the fastest shared steps before and after: a step whose cost
// grows or falls steadily (a pile landing) moves both sides alike.
bool SoloPolicy::verdict(std::uint64_t before_ns, std::uint64_t after_ns, std::uint64_t alone_ns) {
  if (10 * alone_ns < 19 * ((before_ns + after_ns) / 4)) {  // alone a twentieth faster
    won_ = won_ > 0 ? std::min(2 * won_, kMost) : kWonFirst;
    left_ = won_;
    won_stretch_ = true;
    gap_ = kProbeEvery;
    until_probe_ = 0;  // time the cores again once the stretch has shared a few steps
    return true;
  }
  won_ = 0;
  gap_ = std::min(2 * gap_, kMost);
  until_probe_ = gap_;
  return false;
}

}  // namespace tumble
