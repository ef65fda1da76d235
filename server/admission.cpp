#include "admission.hpp"

#include <algorithm>
#include <cmath>

namespace tumble::server {

ConnectionCount::Slot ConnectionCount::try_acquire() {
  {
    std::lock_guard lock(mutex_);
    if (open_ >= max_) return nullptr;
    ++open_;
  }
  return Slot(this, [](void* self) {
    auto* count = static_cast<ConnectionCount*>(self);
    std::lock_guard lock(count->mutex_);
    --count->open_;
  });
}

std::size_t ConnectionCount::open() const {
  std::lock_guard lock(mutex_);
  return open_;
}

int ReadBudget::admit(const std::string& client, double cost) {
  if (rate_ <= 0.0) return 0;
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard lock(mutex_);
  if (buckets_.size() > 4096) {  // Forget clients whose bucket has refilled.
    std::erase_if(buckets_, [&](const auto& kv) {
      const double refill = std::chrono::duration<double>(now - kv.second.at).count() * rate_;
      return kv.second.tokens + refill >= burst_;
    });
  }
  auto [it, fresh] = buckets_.try_emplace(client, Bucket{burst_, now});
  Bucket& b = it->second;
  const double elapsed = std::chrono::duration<double>(now - b.at).count();
  b.tokens = std::min(burst_, b.tokens + elapsed * rate_);
  b.at = now;
  if (b.tokens <= 0.0) return std::max(1, static_cast<int>(std::ceil(-b.tokens / rate_)));
  b.tokens -= cost;
  return 0;
}

}  // namespace tumble::server
