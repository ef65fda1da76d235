#include "contact_colours.hpp"

#include <algorithm>
#include <bit>

namespace tumble {

// Greedy colouring in contact order (Box2D v3's constraint graph, Catto 2024 "Solver2D" and
// "SIMD matters": colours are assigned as contacts begin; here they are recomputed each step,
// which costs one pass over the contacts and keeps the result a function of the contact list
// alone). A pile of boxes, about six neighbours each, needs about eight colours; the floor is
// static and shared by every colour. Within a colour the contacts touch disjoint bodies, so
// sweeping a colour in parallel gives bit for bit the sweep in order; the sweep order as a
// whole (colour by colour) is the Gauss–Seidel order of the solve.
void colour_contacts(std::span<const std::int32_t> a, std::span<const std::int32_t> b,
                     std::size_t body_count, ContactColours& out) {
  const std::size_t n = a.size();
  out.used.assign(body_count, 0);
  out.colour.resize(n);
  out.offset.assign(kMaxColours + 2, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t taken = (a[i] >= 0 ? out.used[a[i]] : 0) | (b[i] >= 0 ? out.used[b[i]] : 0);
    const int c = std::min(std::countr_one(taken), kMaxColours);
    if (c < kMaxColours) {
      const std::uint64_t bit = std::uint64_t{1} << c;
      if (a[i] >= 0) out.used[a[i]] |= bit;
      if (b[i] >= 0) out.used[b[i]] |= bit;
    }
    out.colour[i] = static_cast<std::uint8_t>(c);
    ++out.offset[c + 1];
  }
  for (std::size_t k = 1; k < out.offset.size(); ++k) out.offset[k] += out.offset[k - 1];
  out.order.resize(n);
  // The counts become fill positions; the fill runs in contact order (stable).
  std::vector<std::uint32_t>& next = out.offset;
  for (std::size_t i = 0; i < n; ++i) out.order[next[out.colour[i]]++] = static_cast<std::uint32_t>(i);
  // next[k] is now the end of colour k: shift back into starts.
  for (std::size_t k = next.size() - 1; k > 0; --k) next[k] = next[k - 1];
  next[0] = 0;
}

}  // namespace tumble
