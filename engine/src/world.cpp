#include "tumble/world.hpp"

#include <cmath>
#include <string>
#include <utility>

#include "floor_contact.hpp"
#include "pass_snapshot.hpp"
#include "pipeline.hpp"

namespace tumble {
namespace {

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
  if (threads != pool_->threads()) pool_ = std::make_unique<WorkerPool>(threads);
}

unsigned World::threads() const { return pool_->threads(); }

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
