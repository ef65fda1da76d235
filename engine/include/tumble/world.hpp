#pragma once
/// The World: bodies, a floor and gravity, stepped by a fixed list of stages.
///
/// Usage:
///   tumble::World world(scene);          // scene checked with tumble::validate first
///   for (int i = 0; i < 300; ++i) world.step();
///   world.apply_impulse(0, {0, 5, 0}, world.body(0).s.x);
///
/// Not thread-safe: one thread owns a World (the server's simulation thread). No I/O, no
/// exceptions inside step(); bad input is refused at the entry points.
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <vector>

#include "tumble/body.hpp"
#include "tumble/scene.hpp"
#include "tumble/step_stats.hpp"

namespace tumble {

/// Index of a body in its World (its position in the scene's list).
using BodyId = std::uint32_t;

/// Body–body contact data kept between steps (engine/src/contact_stage.hpp).
struct ContactState;

/// Thrown by World's entry points for input that names no body or is not finite.
struct InvalidInput : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// A simulated world. Deterministic: the same scene and calls give bit-identical states.
class World {
 public:
  /// Builds the world; throws InvalidInput with the field when validate(scene) fails.
  explicit World(Scene scene);
  /// Deep copies (the contact cache included) and moves.
  World(const World& other);
  World& operator=(const World& other);
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;
  ~World();

  /// Advances by the scene's dt.
  void step();
  /// Advances by dt seconds (dt > 0 and finite, else InvalidInput).
  void step(double dt);

  /// Applies impulse J (N·s, world) at world point p (m): ΔP = J, ΔL = (p − x) × J.
  /// Wakes the body. Throws InvalidInput for an unknown id or non-finite values.
  void apply_impulse(BodyId id, const Vec3& impulse, const Vec3& point);
  /// Same, at the centre of mass.
  void apply_impulse(BodyId id, const Vec3& impulse);

  /// Switches the flight integrator from the next step on.
  void set_integrator(Integrator integrator);
  /// Switches the impact-time method from the next step on.
  void set_toi_method(ToiMethod method);

  /// All bodies, indexed by BodyId.
  std::span<const Body> bodies() const { return bodies_; }
  /// One body; throws InvalidInput when id is out of range.
  const Body& body(BodyId id) const;
  /// Looks a body up by name; returns false when there is none.
  bool find_body(std::string_view name, BodyId& id) const;

  /// The scene this world was built from, with the current integrator and TOI method.
  const Scene& scene() const { return scene_; }
  /// Settings in use.
  const WorldDef& settings() const { return scene_.world; }
  /// Simulated time, s.
  double time() const { return time_; }
  /// Steps taken.
  std::uint64_t step_count() const { return steps_; }
  /// Counters of the last step.
  const StepStats& last_step() const { return last_; }
  /// Impacts since construction.
  std::uint64_t total_impacts() const { return total_impacts_; }
  /// Sum of every non-frozen body's kinetic + potential energy, J.
  double total_energy() const;
  /// Bodies currently awake.
  std::size_t awake_count() const;
  /// Bodies frozen after going non-finite.
  std::size_t frozen_count() const;

 private:
  Scene scene_;
  std::vector<Body> bodies_;
  double time_ = 0.0;
  std::uint64_t steps_ = 0;
  std::uint64_t total_impacts_ = 0;
  StepStats last_;
  std::unique_ptr<ContactState> contact_;  // broad phase, contact cache, islands, sleep groups
};

}  // namespace tumble
