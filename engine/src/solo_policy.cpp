#include "solo_policy.hpp"

#include <algorithm>

namespace tumble {

bool SoloPolicy::next_solo(std::uint64_t wall_ns, std::uint64_t stalled_ns) {
  if (left_ > 0) {  // a step alone; after the last one, a shared step tries the cores again
    if (--left_ == 0) since_ = 0;
    return left_ > 0;
  }
  if (4 * stalled_ns > wall_ns && stalled_ns > kLeastStall) {
    length_ = since_ < kRecent ? std::min(2 * length_, kMost) : kFirst;
    left_ = length_;
    return true;
  }
  since_ = std::min(since_ + 1, kRecent);
  return false;
}

}  // namespace tumble
