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
  StepScratch& s = ctx.scratch;
  const bool renormalize = (ctx.step_index + 1) % kGramSchmidtInterval == 0;
  for (std::size_t k = 0; k < s.stepped.size(); ++k) {
    Body& b = ctx.bodies[s.stepped[k]];
    if (!state_finite(b.s)) {
      b.s = s.before[k];
      b.activity = Activity::frozen;
      ++ctx.cache.activity_epoch;
      ++ctx.stats.newly_frozen;
      continue;
    }
    if (renormalize) gram_schmidt(b.s.R);
  }
}

}  // namespace tumble
