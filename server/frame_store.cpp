#include "frame_store.hpp"

#include "frame.hpp"

namespace tumble::server {

void FrameStore::publish(std::shared_ptr<const FrameState> state,
                         std::shared_ptr<const SceneInfo> scene,
                         std::shared_ptr<const nlohmann::json> status,
                         std::shared_ptr<const std::string> contacts,
                         std::uint64_t contacts_step) {
  std::lock_guard lock(mutex_);
  // Sessions always take the newest frame: older encodings are never asked for again
  // (a session writing one holds its own reference).
  std::erase_if(cache_, [&](const auto& kv) { return kv.first.first != state->number; });
  newest_.state = std::move(state);
  newest_.scene = std::move(scene);
  newest_.contacts = std::move(contacts);
  newest_.contacts_step = contacts_step;
  if (status) {
    newest_.status = std::move(status);
    ++newest_.status_sequence;
  }
}

Published FrameStore::newest() const {
  std::lock_guard lock(mutex_);
  return newest_;
}

std::shared_ptr<const std::string> FrameStore::encoded(
    const std::shared_ptr<const FrameState>& state, const FrameState* base) {
  std::shared_ptr<Entry> entry;
  {
    std::lock_guard lock(mutex_);
    auto& slot = cache_[{state->number, base ? std::uint64_t{base->number} + 1 : 0}];
    if (!slot) slot = std::make_shared<Entry>();
    entry = slot;
  }
  // Encoded outside the lock, once per key: the first session to ask does the work, the
  // others in step wait for it and share the bytes.
  std::call_once(entry->once, [&] {
    entry->bytes = std::make_shared<const std::string>(encode_frame(*state, base));
    std::lock_guard lock(mutex_);
    ++encodings_;
  });
  return entry->bytes;
}

std::uint64_t FrameStore::encodings() const {
  std::lock_guard lock(mutex_);
  return encodings_;
}

}  // namespace tumble::server
