#pragma once
/// Colouring of the contacts of one solve: no two contacts of one colour share a moving body,
/// and colour by colour the sweep meets every body's contacts in contact order, so the
/// contacts of a colour can take their impulses at the same time, on any number of threads,
/// with the result of the sequential sweep. Pure functions over the caller's buffers;
/// thread-safe.
#include <cstdint>
#include <span>
#include <vector>

namespace tumble {

/// The contacts grouped by colour: colour k holds order[offset[k] .. offset[k + 1]), in
/// ascending contact index.
struct ContactColours {
  std::vector<std::uint32_t> order;   ///< Contact indices, colour by colour.
  std::vector<std::uint32_t> offset;  ///< Start of each colour in `order`, plus the end.
  std::vector<std::uint32_t> rank_a;  ///< Contacts of each contact's body a before it.
  std::vector<std::uint32_t> rank_b;  ///< Contacts of each contact's body b before it.
  std::vector<std::uint32_t> degree;  ///< Contacts of each body.
  std::vector<std::uint32_t> latest;  ///< Scratch: one past each body's latest colour.
  std::vector<std::uint32_t> colour;  ///< Scratch: colour of each contact.
  /// Number of colours.
  std::size_t count() const { return offset.empty() ? 0 : offset.size() - 1; }
  /// Contact indices of colour k.
  std::span<const std::uint32_t> of(std::size_t k) const {
    return {order.data() + offset[k], order.data() + offset[k + 1]};
  }
};

/// Colours contacts between bodies `a[i]` and `b[i]` (indices below body_count, or −1 for
/// the static floor, which never constrains a colour): each contact's colour is one more than
/// the latest colour of its bodies so far; each contact's rank among its bodies' contacts and
/// each body's degree with them. Deterministic: depends only on the contact order.
void colour_contacts(std::span<const std::int32_t> a, std::span<const std::int32_t> b,
                     std::size_t body_count, ContactColours& out);

}  // namespace tumble
