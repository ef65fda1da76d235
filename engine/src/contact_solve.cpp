#include <algorithm>

#include "pipeline.hpp"

namespace tumble {
namespace {

std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) {
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

/// Starts each contact from the impulses its pair had last step (matched by key); each
/// contact on its own, shared among the pool's threads. The contacts come in two sorted runs
/// of keys (the floor's, then the box–box pairs'), as last step's sorted keys do, so each key
/// is found by walking on from the one before; a binary search only where a run starts over.
/// With a search for every contact, `contact_solve`'s own samples (the search was inlined
/// there) were 1.0 % of `pile`'s, against 0.35 % with the walk (`perf`, the same bits).
void warm_start(StepContext& ctx) {
  using Entry = std::pair<std::uint64_t, std::uint32_t>;
  const ContactCache& cache = ctx.cache;
  std::span<Contact> contacts = ctx.scratch.contacts;
  const std::span<const Entry> keys(cache.previous_keys);
  ctx.pool.for_each(contacts.size(), 64, [&](std::size_t begin, std::size_t end) {
    auto at = keys.begin();
    std::uint64_t last = 0;
    for (std::size_t i = begin; i < end; ++i) {
      Contact& c = contacts[i];
      const std::uint64_t key = pair_key(c.a, c.b);
      if (i == begin || key < last) {
        at = std::lower_bound(keys.begin(), keys.end(), key,
                              [](const Entry& e, std::uint64_t k) { return e.first < k; });
      } else {
        while (at != keys.end() && at->first < key) ++at;
      }
      last = key;
      if (at != keys.end() && at->first == key) warm_start_from(c, cache.previous[at->second]);
    }
  });
}

/// Keeps this step's contacts (with their impulses) for the next step's warm start, their keys
/// read on the pool (a contact is ~1 KB: one cache miss each on one thread). The narrow phase
/// lists the floor's contacts (body a = kStaticBody, the largest key) in body order and then
/// the box–box ones in pair order: two sorted runs, put in order by a rotation (a sort of the
/// keys was 1 % of `pile`, on one thread); a sort if ever they are not.
/// The scratch list takes the contacts of the step before as they are, not emptied: the next
/// narrow phase writes every contact it lists in full, and resizing an emptied list first
/// default-constructed every ~1 KB contact on the owner's thread (`pile`: ~1.5 MB a step,
/// ~0.1 ms while the other thread waited).
void keep_for_warm_start(StepContext& ctx) {
  ContactCache& cache = ctx.cache;
  std::swap(cache.previous, ctx.scratch.contacts);
  auto& keys = cache.previous_keys;
  keys.resize(cache.previous.size());
  ctx.pool.for_each(keys.size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      keys[i] = {pair_key(cache.previous[i].a, cache.previous[i].b), static_cast<std::uint32_t>(i)};
  });
  const auto mid = std::is_sorted_until(keys.begin(), keys.end());
  if (mid == keys.end()) return;
  if (std::is_sorted(mid, keys.end()) && keys.back() < keys.front())
    std::rotate(keys.begin(), mid, keys.end());
  else
    std::sort(keys.begin(), keys.end());
}

}  // namespace

void contact_solve(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  PassClock clock(ctx.timed ? ctx.stats.solve_pass_ns.data() : nullptr);
  if (!s.contacts.empty()) {
    warm_start(ctx);
    clock.lap(SolvePass::cache);
    ctx.stats.impacts += static_cast<std::uint32_t>(
        solve_contacts(ctx.bodies, s.solver_bodies, s.contacts, ctx.world.gravity, ctx.dt,
                       SolverSettings{}, s.solver, ctx.pool, clock));
    ctx.stats.colours = static_cast<std::uint32_t>(s.solver.colours.count());
  }
  keep_for_warm_start(ctx);
  clock.lap(SolvePass::cache);
}

}  // namespace tumble
