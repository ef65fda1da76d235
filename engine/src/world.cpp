#include "tumble/world.hpp"

#include <cmath>
#include <string>

#include "contact_stage.hpp"
#include "floor_contact.hpp"
#include "integrators.hpp"

namespace tumble {
namespace {

constexpr double kSleepSpeed = 0.01;  // m/s: fastest point of a body that may fall asleep.
constexpr double kSleepTime = 0.5;    // s of stillness in contact before sleeping.

/// Stage: a body that has been slow while touching the floor for kSleepTime falls asleep
/// (its momenta are zeroed, so it is exactly still); Box2D's rule, Catto 2023 "islands".
void update_sleep(Body& b, bool touched, double dt) {
  if (!touched) {
    b.still_time = 0.0;
    return;
  }
  const double speed = (b.s.P * b.c.inv_mass).norm() +
                       angular_velocity(b.s, b.c).norm() * b.c.bounding_radius;
  if (speed > kSleepSpeed) {
    b.still_time = 0.0;
    return;
  }
  b.still_time += dt;
  if (b.still_time >= kSleepTime) {
    b.activity = Activity::asleep;
    b.s.P.setZero();
    b.s.L.setZero();
  }
}

/// Stage: the cheap finiteness check; a body that went non-finite keeps its last finite
/// state and is frozen (MuJoCo's mj_checkPos idea), so nothing passes a NaN on.
bool state_finite(const BodyState& s) {
  return std::isfinite(s.x.sum() + s.P.sum() + s.L.sum() + s.R.sum());
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
    // A body placed still on a face on the floor starts asleep: it costs nothing from the
    // first step instead of after the sleep timer.
    if (w.floor && rests_on_face(b.s, b.c, w.floor->height)) b.activity = Activity::asleep;
    bodies_.push_back(b);
  }
  contact_ = std::make_unique<ContactState>();
  init_contact_state(*contact_, bodies_.size());
}

World::World(const World& other)
    : scene_(other.scene_),
      bodies_(other.bodies_),
      time_(other.time_),
      steps_(other.steps_),
      total_impacts_(other.total_impacts_),
      last_(other.last_),
      contact_(std::make_unique<ContactState>(*other.contact_)) {}

World& World::operator=(const World& other) {
  if (this != &other) *this = World(other);
  return *this;
}

World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;
World::~World() = default;

void World::step() { step(scene_.world.dt); }

void World::step(double dt) {
  if (!(std::isfinite(dt) && dt > 0.0)) throw InvalidInput("dt must be finite and > 0");
  last_ = {};
  const WorldDef& w = scene_.world;
  const bool renormalize = (steps_ + 1) % kGramSchmidtInterval == 0;
  // Body–body contact runs only when two bodies can touch; otherwise every body takes the
  // floor-only path below, bit for bit as without it.
  const bool contacts = find_contacts(*contact_, bodies_, w, dt, last_);
  for (std::size_t i = 0; i < bodies_.size(); ++i) {
    Body& b = bodies_[i];
    if (b.activity != Activity::awake || contact_->in_solver[i]) continue;
    ++last_.awake;
    const BodyState before = b.s;
    const FloorStepResult r = advance_with_floor(b, w, dt);
    last_.impacts += r.impacts;
    last_.toi_iterations += r.toi_iterations;
    b.in_contact = r.touched;
    if (!state_finite(b.s)) {
      b.s = before;
      b.activity = Activity::frozen;
      ++last_.newly_frozen;
      continue;
    }
    if (renormalize) gram_schmidt(b.s.R);
    update_sleep(b, r.touched, dt);
    if (b.activity == Activity::asleep) sleep_alone(*contact_, static_cast<std::uint32_t>(i));
  }
  if (contacts) step_contacts(*contact_, bodies_, w, dt, renormalize, last_);
  total_impacts_ += last_.impacts;
  time_ += dt;
  ++steps_;
}

void World::apply_impulse(BodyId id, const Vec3& impulse, const Vec3& point) {
  require_finite(impulse, "impulse");
  require_finite(point, "point");
  body(id);  // validates the id
  Body& b = bodies_[id];
  if (b.activity == Activity::frozen) throw InvalidInput("body is frozen (it went non-finite)");
  b.s.P += impulse;
  b.s.L += (point - b.s.x).cross(impulse);
  wake_island(*contact_, bodies_, id);
}

void World::apply_impulse(BodyId id, const Vec3& impulse) {
  body(id);
  apply_impulse(id, impulse, bodies_[id].s.x);
}

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
