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

// One rule for every stepped body: a body that went non-finite keeps its last finite state and
// is frozen (MuJoCo's mj_checkPos idea), so nothing passes a NaN on; every
// kGramSchmidtInterval steps R is re-orthonormalised.
void finalize(StepContext& ctx) {
  constexpr std::size_t kGrain = 512;  // bodies per chunk: ~10 ns each
  StepScratch& s = ctx.scratch;
  const bool renormalize = (ctx.step_index + 1) % kGramSchmidtInterval == 0;
  ctx.pool.for_each(s.stepped.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    std::uint32_t frozen = 0;
    for (std::size_t k = begin; k < end; ++k) {
      Body& b = ctx.bodies[s.stepped[k]];
      if (!state_finite(b.s)) {
        b.s = s.before[k];
        b.activity = Activity::frozen;
        ++frozen;
        continue;
      }
      if (renormalize) gram_schmidt(b.s.R);
    }
    if (frozen) std::atomic_ref(ctx.stats.newly_frozen).fetch_add(frozen);
  });
  if (ctx.stats.newly_frozen > 0) ++ctx.cache.activity_epoch;
}

}  // namespace tumble
