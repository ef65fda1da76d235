#include "scenes.hpp"

#include <cmath>
#include <random>

#include "tumble/scene_io.hpp"

namespace tumble_bench {

tumble::Scene bundled(const std::string& name) { return tumble::load_scene(name); }

tumble::Scene with(tumble::Scene s, tumble::Integrator integrator, tumble::ToiMethod toi,
                   double dt) {
  s.world.integrator = integrator;
  s.world.toi = toi;
  s.world.dt = dt;
  return s;
}

namespace {

/// A uniformly random rotation: a normalised quaternion of four normal draws. The draws are
/// named, in order: as a call's arguments their order was unspecified (GCC evaluates them
/// right to left, Clang left to right), and the same seed gave each compiler another scene.
/// The names keep the order of GCC's builds, whose runs the docs record.
tumble::Quat random_orientation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double z = n(rng), y = n(rng), x = n(rng), w = n(rng);
  tumble::Quat q(w, x, y, z);
  q.normalize();
  return q;
}

tumble::Scene empty_floor_scene(const std::string& name, double dt) {
  tumble::Scene s;
  s.world.name = name;
  s.world.dt = dt;
  s.world.floor = tumble::Floor{0.0, 0.5, 0.0};
  s.world.integrator = tumble::Integrator::exact;
  s.world.toi = tumble::ToiMethod::root;
  return s;
}

}  // namespace

const char* to_string(BoxShape shape) { return shape == BoxShape::cube ? "cube" : "box"; }

tumble::Scene separated_boxes(std::size_t n, double dt, unsigned seed, BoxShape shape) {
  tumble::Scene s = empty_floor_scene("separated_boxes", dt);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> size(0.2, 0.6), mass(1.0, 10.0), height(1.0, 3.0),
      spin(-3.0, 3.0);
  const auto side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  constexpr double kSpacing = 1.5;  // m; > the largest box diagonal (1.04 m).
  s.bodies.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    tumble::BodyDef b;
    b.name = "box" + std::to_string(i);
    b.size = {size(rng), size(rng), size(rng)};
    if (shape == BoxShape::cube) b.size = Vec3::Constant(b.size.x());
    b.mass = mass(rng);
    b.position = {kSpacing * static_cast<double>(i % side), height(rng),
                  kSpacing * static_cast<double>(i / side)};
    b.orientation = random_orientation(rng);
    b.angular_velocity = {spin(rng), spin(rng), spin(rng)};
    s.bodies.push_back(b);
  }
  return s;
}

tumble::Scene landing_cubes(std::size_t n, unsigned seed) {
  tumble::Scene s = empty_floor_scene("landing_cubes", 1.0 / 240.0);
  s.world.floor = tumble::Floor{0.0, 0.0, 1.0};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> height(1.0, 3.0), spin(-3.0, 3.0);
  const auto side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  constexpr double kSpacing = 3.0;  // m
  s.bodies.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    tumble::BodyDef b;
    b.name = "cube" + std::to_string(i);
    b.position = {kSpacing * static_cast<double>(i % side), height(rng),
                  kSpacing * static_cast<double>(i / side)};
    b.orientation = random_orientation(rng);
    b.angular_velocity = {spin(rng), spin(rng), spin(rng)};
    s.bodies.push_back(b);
  }
  return s;
}

tumble::Scene resting_and_falling(std::size_t resting, std::size_t falling) {
  tumble::Scene s = empty_floor_scene("resting_and_falling", 1.0 / 60.0);
  const auto side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(resting))));
  constexpr double kSpacing = 2.0;
  for (std::size_t i = 0; i < resting; ++i) {
    tumble::BodyDef b;
    b.name = "rest" + std::to_string(i);
    b.position = {kSpacing * static_cast<double>(i % side), 0.5,
                  kSpacing * static_cast<double>(i / side)};
    s.bodies.push_back(b);
  }
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> spin(-2.0, 2.0);
  for (std::size_t i = 0; i < falling; ++i) {
    tumble::BodyDef b;
    b.name = "fall" + std::to_string(i);
    b.position = {kSpacing * static_cast<double>(i), 2.0, -4.0};
    b.orientation = random_orientation(rng);
    b.angular_velocity = {spin(rng), spin(rng), spin(rng)};
    s.bodies.push_back(b);
  }
  return s;
}

tumble::Scene free_spin(const tumble::Vec3& size, double mass,
                        const tumble::Vec3& angular_velocity, double dt) {
  tumble::Scene s;
  s.world.name = "free_spin";
  s.world.gravity.setZero();
  s.world.floor.reset();
  s.world.dt = dt;
  tumble::BodyDef b;
  b.size = size;
  b.mass = mass;
  b.angular_velocity = angular_velocity;
  s.bodies.push_back(b);
  return s;
}

PeerScene to_peer(const tumble::Scene& s) {
  PeerScene p;
  p.gravity = s.world.gravity;
  p.floor = s.world.floor.has_value();
  const double floor_y = p.floor ? s.world.floor->height : 0.0;
  p.restitution = p.floor ? s.world.floor->restitution : 0.0;
  p.friction = p.floor ? s.world.floor->friction : 0.0;
  p.dt = s.world.dt;
  for (const tumble::BodyDef& b : s.bodies) {
    PeerBox box;
    box.size = b.size;
    box.mass = b.mass;
    box.position = b.position - Vec3(0.0, floor_y, 0.0);
    box.orientation = b.orientation.normalized();
    box.velocity = b.velocity;
    box.angular_velocity = b.angular_velocity;
    p.boxes.push_back(box);
  }
  return p;
}

}  // namespace tumble_bench
