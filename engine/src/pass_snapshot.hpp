#pragma once
/// What World::step keeps to take a pass again under WorldDef::max_overlap (world_step.cpp).
#include <algorithm>
#include <cstdint>
#include <vector>

#include "pipeline.hpp"

namespace tumble {

/// What the rest of a pass can change once its contacts are found, kept to take it again:
/// the awake bodies (the others stay as they are), the contact cache and the pass count.
struct PassSnapshot {
  bool taken = false;                // the pass had pairs to check (else nothing was kept)
  std::vector<std::uint32_t> ids;    // the awake bodies, ascending
  std::vector<Body> bodies;          // their records
  ContactCache cache;
  std::uint64_t passes = 0;
};

/// Copies `from` into `to`, growing `to` to `from`'s capacity whenever it must grow at all.
/// A vector's plain copy grows only to the size it copies, so a copy made every pass would
/// allocate again at each new contact; this one allocates only after `from` itself grew.
template <class T>
void copy_into(std::vector<T>& to, const std::vector<T>& from) {
  if (to.capacity() < from.size()) to.reserve(std::max(from.capacity(), 2 * to.capacity()));
  to.assign(from.begin(), from.end());
}

/// Copies a contact cache field by field with copy_into.
inline void copy_cache(ContactCache& to, const ContactCache& from) {
  static_assert(sizeof(ContactCache) == 6 * sizeof(std::vector<int>) + sizeof(std::uint64_t),
                "a field added to ContactCache must be copied here too");
  copy_into(to.sleep_next, from.sleep_next);
  copy_into(to.anchors, from.anchors);
  copy_into(to.previous, from.previous);
  copy_into(to.previous_keys, from.previous_keys);
  copy_into(to.record_pairs, from.record_pairs);
  copy_into(to.records, from.records);
  to.activity_epoch = from.activity_epoch;
}


}  // namespace tumble
