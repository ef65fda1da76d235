#include <atomic>
#include <cmath>

#include "integrators.hpp"
#include "pipeline.hpp"

namespace tumble {
namespace {

/// The cheap finiteness check of a whole state.
bool state_finite(const BodyState& s) {
  return std::isfinite(s.x.sum() + s.P.sum() + s.L.sum() + s.R.sum());
}

}  // namespace

bool renormalize_after(std::uint64_t step_index) {
  return (step_index + 1) % kGramSchmidtInterval == 0;
}

bool finalize_body(Body& b, const BodyState& before, bool renormalize) {
  if (!state_finite(b.s)) {
    b.s = before;
    b.activity = Activity::frozen;
    return false;
  }
  if (renormalize) gram_schmidt(b.s.R);
  return true;
}

// One rule for every stepped body: a body that went non-finite keeps its last finite state and
// is frozen (MuJoCo's mj_checkPos idea), so nothing passes a NaN on; every
// kGramSchmidtInterval steps R is re-orthonormalised. Lone bodies took the rule in flight
// (finalize_body), island bodies take it here.
void finalize(StepContext& ctx) {
  constexpr std::size_t kGrain = 512;  // bodies per chunk: ~10 ns each
  StepScratch& s = ctx.scratch;
  const bool renormalize = renormalize_after(ctx.step_index);
  ctx.pool.for_each(s.solver_bodies.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    std::uint32_t frozen = 0;
    for (std::size_t k = begin; k < end; ++k)
      frozen += finalize_body(ctx.bodies[s.solver_bodies[k]], s.before[k], renormalize) ? 0 : 1;
    if (frozen) std::atomic_ref(ctx.stats.newly_frozen).fetch_add(frozen);
  });
  if (ctx.stats.newly_frozen > 0) ++ctx.cache.activity_epoch;
}

}  // namespace tumble
