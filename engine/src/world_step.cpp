/// World::step: one pass of the stages (engine/src/pipeline.hpp), or with WorldDef::max_overlap
/// as many as keep the bound. The rest of the World is in world.cpp.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "overlap_bound.hpp"
#include "pass_snapshot.hpp"
#include "pipeline.hpp"
#include "tumble/world.hpp"

namespace tumble {
namespace {

// A contact with a sleeping island wakes it; its bodies then need their own contacts, so the
// detection stages repeat (rarely more than once) until nothing new wakes.
constexpr int kMaxWakeRounds = 8;

/// Runs one stage and, when the World times its stages, adds its wall time to the counters.
void run_stage(Stage stage, void (*run)(StepContext&), StepContext& ctx, bool timed) {
  if (!timed) return run(ctx);
  const auto start = std::chrono::steady_clock::now();
  run(ctx);
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::steady_clock::now() - start);
  ctx.stats.stage_ns[static_cast<int>(stage)] += static_cast<std::uint64_t>(ns.count());
}

}  // namespace

void World::step() { step(scene_.world.dt); }

// The step as a list of stages (engine/src/pipeline.hpp says what each does and where).
void World::step(double dt) {
  if (!(std::isfinite(dt) && dt > 0.0)) throw InvalidInput("dt must be finite and > 0");
  last_ = {};
  const WorkerPool::Busy busy(*pool_);  // workers poll through the step's serial stretches
  if (scene_.world.max_overlap > 0.0) {
    step_within_overlap(dt);
  } else {
    pass(dt, last_, nullptr);
    total_impacts_ += last_.impacts;
  }
  last_.solo = pool_->solo() ? 1 : 0;
  time_ += dt;
  ++steps_;
}

// Inlined into its two callers: as a call of its own it cost a lone body's step 26 of its
// ~1,240 instructions (callgrind, `bounce`).
[[gnu::always_inline]] inline void World::pass(double dt, StepStats& stats,
                                               PassSnapshot* keep) {
  StepContext ctx{scene_.world, dt,        passes_, bodies_, *cache_,
                  *broad_,       *scratch_,  stats,   *pool_,  time_stages_,
                  unequal_moments_ > 0};
  for (int round = 0; round < kMaxWakeRounds; ++round) {
    run_stage(Stage::broad_phase, broad_phase, ctx, time_stages_);
    run_stage(Stage::narrow_phase, narrow_phase, ctx, time_stages_);
    if (ctx.scratch.woken == 0) break;
  }
  if (keep) take_snapshot(*keep);
  run_stage(Stage::islands, islands, ctx, time_stages_);
  run_stage(Stage::contact_solve, contact_solve, ctx, time_stages_);
  run_stage(Stage::flight, flight, ctx, time_stages_);
  run_stage(Stage::finalize, finalize, ctx, time_stages_);
  run_stage(Stage::sleep, update_sleep, ctx, time_stages_);
  stats.passes = 1;
  ++passes_;
}

namespace {

/// Adds a kept pass's counters to the step's: what happened is summed over the kept passes
/// (impacts, their searches, bodies frozen, the pair budget), the picture of the world (pairs,
/// contacts, islands …) is the last kept pass's, and the times and pass counts stay the step's
/// (add_times counts every pass, kept or not).
void add_kept(StepStats& step, const StepStats& pass) {
  StepStats sum = pass;
  sum.impacts += step.impacts;
  sum.toi_iterations += step.toi_iterations;
  sum.newly_frozen += step.newly_frozen;
  sum.pair_budget_exceeded |= step.pair_budget_exceeded;
  sum.stage_ns = step.stage_ns;
  sum.solve_pass_ns = step.solve_pass_ns;
  sum.passes = step.passes;
  sum.halved_passes = step.halved_passes;
  step = sum;
}

/// Adds a pass's stage times to the step's.
void add_times(StepStats& step, const StepStats& pass) {
  for (int i = 0; i < kStageCount; ++i) step.stage_ns[i] += pass.stage_ns[i];
  for (int i = 0; i < kSolvePassCount; ++i) step.solve_pass_ns[i] += pass.solve_pass_ns[i];
  ++step.passes;
}

}  // namespace

// A pass that opens an overlap deeper than max_overlap is undone (bodies, contact cache and
// the pass count restored; the broad phase's acceleration rebuilt, which changes no result)
// and taken again as two passes of dt / 2, each checked the same way, down to kMaxHalvings
// halvings, where a pass is kept whatever it opens (overlap_bound.cpp says why). As an
// adaptive integrator grows its step after a success, a step starts with the halvings the
// step before ended with, less one when that one had to undo nothing: in `pile` the steps
// that need halving come in runs, and starting each from dt took a quarter more passes.
void World::step_within_overlap(double dt) {
  const int start = halvings_;
  finest_ = start;
  const int parts = 1 << start;
  for (int k = 0; k < parts; ++k) step_passes(dt / parts, start);
  halvings_ = last_.halved_passes == 0 ? std::max(0, start - 1) : finest_;
}

void World::step_passes(double dt, int halvings) {
  StepStats stats;
  finest_ = std::max(finest_, halvings);
  // One snapshot serves every level: a failed pass is put back from it before its halves
  // take theirs, and a pass that keeps the bound never goes back.
  if (!snapshot_) snapshot_ = std::make_unique<PassSnapshot>();
  PassSnapshot* kept = halvings < kMaxHalvings ? snapshot_.get() : nullptr;
  pass(dt, stats, kept);
  add_times(last_, stats);
  if (!kept || !kept->taken ||
      overlap_grown(kept->ids, kept->bodies, bodies_, scratch_->pairs, scene_.world,
                    scene_.world.max_overlap, *pool_) == 0.0) {
    add_kept(last_, stats);
    total_impacts_ += stats.impacts;
    return;
  }
  ++last_.halved_passes;
  for (std::size_t k = 0; k < kept->ids.size(); ++k) bodies_[kept->ids[k]] = kept->bodies[k];
  std::swap(*cache_, kept->cache);
  passes_ = kept->passes;
  ++cache_->activity_epoch;  // the broad phase rescans every body and sweeps again
  broad_->fat_valid = false;
  scratch_->earlier_step = ~std::uint64_t{0};  // its answers were for the pass undone
  step_passes(0.5 * dt, halvings + 1);
  step_passes(0.5 * dt, halvings + 1);
}

// Taken after the pass's contacts are found: until then nothing has moved, and only now is it
// known whether the pass has any pair to check. A pass without one (bodies in flight, boxes
// resting apart) keeps nothing and costs what it costs without the bound; lone bodies meet the
// floor at their time of impact, so only pairs can sink (an island's floor contacts included:
// an island is made of pairs).
void World::take_snapshot(PassSnapshot& keep) const {
  keep.taken = !scratch_->pairs.empty();
  if (!keep.taken) return;
  keep.ids.clear();
  keep.bodies.clear();
  for (std::uint32_t i = 0; i < bodies_.size(); ++i) {
    if (bodies_[i].activity != Activity::awake) continue;
    keep.ids.push_back(i);
    keep.bodies.push_back(bodies_[i]);
  }
  copy_cache(keep.cache, *cache_);
  keep.passes = passes_;
}

}  // namespace tumble
