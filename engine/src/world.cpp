#include "tumble/world.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "floor_contact.hpp"
#include "overlap_bound.hpp"
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

/// One snapshot per level of halving, reused from step to step.
struct PassSnapshots {
  std::array<PassSnapshot, kMaxHalvings> levels;
};
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

void require_finite(const Vec3& v, const char* what) {
  if (!all_finite(v)) throw InvalidInput(std::string(what) + " must be finite");
}

}  // namespace

World::World(Scene scene) : scene_(std::move(scene)) {
  if (auto error = validate(scene_)) throw InvalidInput(error->field + ": " + error->message);
  const WorldDef& w = scene_.world;
  const double e = w.floor ? w.floor->restitution : 1.0;
  const double mu = w.floor ? w.floor->friction : 0.0;
  bodies_.reserve(scene_.bodies.size());
  for (const BodyDef& def : scene_.bodies) {
    Body b;
    b.c = make_body_constants(def, e, mu);
    b.s = make_body_state(def, b.c);
    // A body placed still on a face on the floor, where the floor holds it against gravity,
    // starts asleep: it costs nothing from the first step instead of after the sleep timer.
    if (w.floor && rests_on_face(b.s, b.c, w.floor->height, w.gravity))
      b.activity = Activity::asleep;
    if (b.c.shape != InertiaShape::isotropic) ++unequal_moments_;
    bodies_.push_back(b);
  }
  // A scene that packs its bodies into one another costs memory and time quadratic in their
  // number (2,000 boxes at one point: two million pairs); beyond the pair budget it is refused.
  if (initial_pairs(bodies_, w.gravity) > pair_budget(bodies_.size()))
    throw InvalidInput("bodies: more than " + std::to_string(pair_budget(bodies_.size())) +
                       " pairs of bodies overlap as placed (the limit is 32 per body + 1024)");
  cache_ = std::make_unique<ContactCache>();
  broad_ = std::make_unique<BroadPhaseCache>();
  scratch_ = std::make_unique<StepScratch>();
  pool_ = std::make_unique<WorkerPool>(1);
  init_caches(*cache_, bodies_.size());
  prime_broad_phase();
}

// The broad phase keeps every sleeping body's box and the sweep order between steps; built
// here, with the world (as other engines insert a body into their tree when it is created),
// the first step costs what its awake bodies cost instead of a sweep over every body. It
// changes no result: the broad phase's pairs come out the same whatever its cache holds.
void World::prime_broad_phase() {
  StepStats unused;
  StepContext ctx{scene_.world, scene_.world.dt, steps_, bodies_, *cache_,
                  *broad_,      *scratch_,       unused, *pool_, false};
  broad_phase(ctx);
  scratch_->pairs.clear();
}

World::World(const World& other)
    : scene_(other.scene_),
      bodies_(other.bodies_),
      time_(other.time_),
      steps_(other.steps_),
      passes_(other.passes_),
      halvings_(other.halvings_),
      total_impacts_(other.total_impacts_),
      unequal_moments_(other.unequal_moments_),
      last_(other.last_),
      time_stages_(other.time_stages_),
      cache_(std::make_unique<ContactCache>(*other.cache_)),
      broad_(std::make_unique<BroadPhaseCache>()),
      scratch_(std::make_unique<StepScratch>()),
      pool_(std::make_unique<WorkerPool>(other.threads())) {}

World& World::operator=(const World& other) {
  if (this != &other) *this = World(other);
  return *this;
}

World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;
World::~World() = default;

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

/// Adds a kept pass's counters to the step's (times are added for every pass, kept or not).
void add_kept(StepStats& step, const StepStats& pass) {
  const auto times = step.stage_ns;
  const auto passes = step.solve_pass_ns;
  const std::uint32_t impacts = step.impacts + pass.impacts;
  const std::uint32_t toi = step.toi_iterations + pass.toi_iterations;
  const std::uint32_t frozen = step.newly_frozen + pass.newly_frozen;
  const std::uint32_t over = step.pair_budget_exceeded | pass.pair_budget_exceeded;
  const std::uint32_t runs = step.passes, halved = step.halved_passes;
  step = pass;
  step.impacts = impacts;
  step.toi_iterations = toi;
  step.newly_frozen = frozen;
  step.pair_budget_exceeded = over;
  step.stage_ns = times;
  step.solve_pass_ns = passes;
  step.passes = runs;
  step.halved_passes = halved;
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
  if (!snapshots_) snapshots_ = std::make_unique<PassSnapshots>();
  PassSnapshot* kept =
      halvings < kMaxHalvings ? &snapshots_->levels[static_cast<std::size_t>(halvings)] : nullptr;
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
  keep.cache = *cache_;
  keep.passes = passes_;
}

BodyId World::add_body(const BodyDef& def) {
  const std::string at = "bodies[" + std::to_string(bodies_.size()) + "]";
  if (bodies_.size() >= kMaxBodies)
    throw InvalidInput("bodies: at most " + std::to_string(kMaxBodies) + " bodies");
  if (auto error = validate_body(def, at)) throw InvalidInput(error->field + ": " + error->message);
  BodyId existing = 0;
  if (find_body(def.name, existing))
    throw InvalidInput(at + ".name: duplicate body name \"" + def.name + "\"");
  const WorldDef& w = scene_.world;
  Body b;
  b.c = make_body_constants(def, w.floor ? w.floor->restitution : 1.0,
                            w.floor ? w.floor->friction : 0.0);
  b.s = make_body_state(def, b.c);
  const auto id = static_cast<BodyId>(bodies_.size());
  if (b.c.shape != InertiaShape::isotropic) ++unequal_moments_;
  bodies_.push_back(b);
  scene_.bodies.push_back(def);
  init_caches(*cache_, bodies_.size());  // an island of its own
  ++cache_->activity_epoch;  // the broad phase sees a new body: it rescans
  return id;
}

void World::apply_impulse(BodyId id, const Vec3& impulse, const Vec3& point) {
  require_finite(impulse, "impulse");
  require_finite(point, "point");
  body(id);  // validates the id
  Body& b = bodies_[id];
  if (b.activity == Activity::frozen) throw InvalidInput("body is frozen (it went non-finite)");
  b.s.P += impulse;
  b.s.L += (point - b.s.x).cross(impulse);
  wake_island(*cache_, bodies_, id);
  note_moved(*broad_, id, b.s);
}

void World::apply_impulse(BodyId id, const Vec3& impulse) {
  body(id);
  apply_impulse(id, impulse, bodies_[id].s.x);
}

void World::set_stage_timing(bool on) { time_stages_ = on; }

void World::set_threads(unsigned threads) {
  if (threads == 0) threads = hardware_threads();
  if (threads != pool_->size()) pool_ = std::make_unique<WorkerPool>(threads);
}

unsigned World::threads() const { return pool_->size(); }

unsigned World::hardware_threads() { return tumble::hardware_threads(); }

void World::set_integrator(Integrator integrator) { scene_.world.integrator = integrator; }

void World::set_toi_method(ToiMethod method) { scene_.world.toi = method; }

const Body& World::body(BodyId id) const {
  if (id >= bodies_.size())
    throw InvalidInput("no body with index " + std::to_string(id) + " (there are " +
                       std::to_string(bodies_.size()) + ")");
  return bodies_[id];
}

bool World::find_body(std::string_view name, BodyId& id) const {
  for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
    if (scene_.bodies[i].name == name) {
      id = static_cast<BodyId>(i);
      return true;
    }
  }
  return false;
}

double World::total_energy() const {
  double e = 0.0;
  for (const Body& b : bodies_)
    if (b.activity != Activity::frozen) e += tumble::total_energy(b.s, b.c, scene_.world.gravity);
  return e;
}

std::size_t World::awake_count() const {
  std::size_t n = 0;
  for (const Body& b : bodies_) n += b.activity == Activity::awake;
  return n;
}

std::size_t World::frozen_count() const {
  std::size_t n = 0;
  for (const Body& b : bodies_) n += b.activity == Activity::frozen;
  return n;
}

}  // namespace tumble
