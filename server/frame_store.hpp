#pragma once
/// The frames the broadcaster has made, shared by every viewer: the newest FrameState,
/// its encodings cached by base frame (viewers in step share one encoding) and the latest
/// status. Each session keeps the FrameState it last sent as its own delta base, so a base
/// never expires. Thread-safe.
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "frame_state.hpp"
#include "snapshot.hpp"

namespace tumble::server {

/// What one broadcaster tick published.
struct Published {
  std::shared_ptr<const FrameState> state;        ///< Newest frame state (never null).
  std::shared_ptr<const SceneInfo> scene;         ///< Its scene (message sent before it).
  std::shared_ptr<const nlohmann::json> status;   ///< Latest status fields.
  std::uint64_t status_sequence = 0;              ///< +1 per new status.
  /// The "contacts" text message of the newest snapshot's step; null when no viewer asked.
  std::shared_ptr<const std::string> contacts;
  std::uint64_t contacts_step = 0;                ///< The step `contacts` is from.
};

/// Frame history and encoding cache.
class FrameStore {
 public:
  /// Publishes the newest frame; `status` (may be null: unchanged) becomes the latest status;
  /// `contacts` (may be null: none asked for) the contacts message of step `contacts_step`.
  void publish(std::shared_ptr<const FrameState> state, std::shared_ptr<const SceneInfo> scene,
               std::shared_ptr<const nlohmann::json> status,
               std::shared_ptr<const std::string> contacts = nullptr,
               std::uint64_t contacts_step = 0);
  /// The newest publication (state null before the first).
  Published newest() const;
  /// The encoding of `state` relative to `base` (null: keyframe), made once and shared.
  std::shared_ptr<const std::string> encoded(const std::shared_ptr<const FrameState>& state,
                                             const FrameState* base);
  /// Encodings made so far (for tests: viewers in step share them).
  std::uint64_t encodings() const;

 private:
  struct Entry {
    std::once_flag once;
    std::shared_ptr<const std::string> bytes;
  };
  mutable std::mutex mutex_;
  Published newest_;
  // Key: (frame number, base number + 1; 0 for a keyframe). Only the newest frame's.
  std::map<std::pair<std::uint32_t, std::uint64_t>, std::shared_ptr<Entry>> cache_;
  std::uint64_t encodings_ = 0;
};

}  // namespace tumble::server
