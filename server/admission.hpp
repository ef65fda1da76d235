#pragma once
/// Admission limits shared by every connection: the connection cap and the per-client budget
/// for expensive reads. Thread-safe.
#include <chrono>
#include <cstddef>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

namespace tumble::server {

/// Counts open connections (HTTP and WebSocket) against --max-connections.
class ConnectionCount {
 public:
  /// A held place; the count drops when the last copy is destroyed.
  using Slot = std::shared_ptr<void>;

  /// At most `max` places.
  explicit ConnectionCount(std::size_t max) : max_(max) {}
  ConnectionCount(const ConnectionCount&) = delete;
  ConnectionCount& operator=(const ConnectionCount&) = delete;

  /// A place, or nullptr when `max` are held. Thread-safe.
  Slot try_acquire();
  /// Places held now. Thread-safe.
  std::size_t open() const;

 private:
  const std::size_t max_;
  mutable std::mutex mutex_;
  std::size_t open_ = 0;
};

/// A token bucket per client address for reads whose cost grows with the scene (/api/state,
/// /api/scene): `rate` cost units (body records) per second. A request is admitted while
/// the client's bucket is positive and its cost is then taken, possibly into debt, so that a
/// single read larger than the bucket still passes, and the client then waits it off (the
/// average stays at `rate`; Envoy's local rate limit and nginx's limit_req are the same idea
/// with a cost of 1 per request).
class ReadBudget {
 public:
  /// `rate` units/s per client (0: unlimited); a bucket holds at most `burst` units.
  ReadBudget(double rate, double burst) : rate_(rate), burst_(burst) {}

  /// Takes `cost` from `client`'s bucket. Returns 0 when admitted, else the whole seconds
  /// (≥ 1) after which the bucket is positive again (for Retry-After). Thread-safe.
  int admit(const std::string& client, double cost);

 private:
  struct Bucket {
    double tokens;
    std::chrono::steady_clock::time_point at;
  };
  const double rate_;
  const double burst_;
  std::mutex mutex_;
  std::unordered_map<std::string, Bucket> buckets_;
};

}  // namespace tumble::server
