#include "contact_colours.hpp"

#include <algorithm>

namespace tumble {

// Colours that keep the sweep's order (the "waves" of a dependency graph): a contact's colour
// is one more than the latest colour of the contacts before it that share one of its bodies,
// so every body meets its contacts in the same order as in the sweep by contact index, and
// the result is bit for bit that sweep's, on any number of threads. Measured alternative:
// Box2D v3's greedy colouring (each contact takes the lowest colour free at both bodies, Catto
// 2024) needs fewer colours but reorders the sweep, and the order changes from step to step as
// contacts come and go: the 1,000-box `pile` then never settled (853 boxes awake after 20 s,
// all asleep at 9.9 s in contact order). The floor is static and constrains nothing.
void colour_contacts(std::span<const std::int32_t> a, std::span<const std::int32_t> b,
                     std::size_t body_count, ContactColours& out) {
  const std::size_t n = a.size();
  out.latest.assign(body_count, 0);
  out.degree.assign(body_count, 0);
  out.colour.resize(n);
  out.rank_a.resize(n);
  out.rank_b.resize(n);
  std::uint32_t colours = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t c =
        std::max(a[i] >= 0 ? out.latest[a[i]] : 0u, b[i] >= 0 ? out.latest[b[i]] : 0u);
    if (a[i] >= 0) out.latest[a[i]] = c + 1, out.rank_a[i] = out.degree[a[i]]++;
    if (b[i] >= 0) out.latest[b[i]] = c + 1, out.rank_b[i] = out.degree[b[i]]++;
    out.colour[i] = c;
    colours = std::max(colours, c + 1);
  }
  // Counting sort by colour, stable: contact order within a colour.
  out.offset.assign(colours + 1, 0);
  for (std::size_t i = 0; i < n; ++i) ++out.offset[out.colour[i] + 1];
  for (std::size_t k = 1; k < out.offset.size(); ++k) out.offset[k] += out.offset[k - 1];
  out.order.resize(n);
  std::vector<std::uint32_t>& next = out.offset;
  for (std::size_t i = 0; i < n; ++i) out.order[next[out.colour[i]]++] = static_cast<std::uint32_t>(i);
  // next[k] is now the end of colour k: shift back into starts.
  for (std::size_t k = next.size() - 1; k > 0; --k) next[k] = next[k - 1];
  next[0] = 0;
}

}  // namespace tumble
