#include <algorithm>

#include "pipeline.hpp"

namespace tumble {
namespace {

std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) {
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

/// Starts each contact from the impulses its pair had last step (matched by key).
void warm_start(StepContext& ctx) {
  const ContactCache& cache = ctx.cache;
  for (Contact& c : ctx.scratch.contacts) {
    const std::uint64_t key = pair_key(c.a, c.b);
    const auto it = std::lower_bound(
        cache.previous_keys.begin(), cache.previous_keys.end(), key,
        [](const std::pair<std::uint64_t, std::uint32_t>& e, std::uint64_t k) { return e.first < k; });
    if (it != cache.previous_keys.end() && it->first == key)
      warm_start_from(c, cache.previous[it->second]);
  }
}

/// Keeps this step's contacts (with their impulses) for the next step's warm start.
void keep_for_warm_start(StepContext& ctx) {
  ContactCache& cache = ctx.cache;
  std::swap(cache.previous, ctx.scratch.contacts);
  ctx.scratch.contacts.clear();
  cache.previous_keys.clear();
  for (std::size_t i = 0; i < cache.previous.size(); ++i)
    cache.previous_keys.emplace_back(pair_key(cache.previous[i].a, cache.previous[i].b),
                                     static_cast<std::uint32_t>(i));
  std::sort(cache.previous_keys.begin(), cache.previous_keys.end());
}

}  // namespace

void contact_solve(StepContext& ctx) {
  StepScratch& s = ctx.scratch;
  if (!s.contacts.empty()) {
    warm_start(ctx);
    ctx.stats.impacts += static_cast<std::uint32_t>(
        solve_contacts(ctx.bodies, s.solver_bodies, s.contacts, ctx.world.gravity, ctx.dt,
                       SolverSettings{}, s.solver, ctx.pool));
    ctx.stats.colours = static_cast<std::uint32_t>(s.solver.colours.count());
  }
  keep_for_warm_start(ctx);
}

}  // namespace tumble
