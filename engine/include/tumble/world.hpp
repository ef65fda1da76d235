#pragma once
/// The World: bodies, a floor and gravity, stepped by a fixed list of stages.
///
/// Usage:
///   tumble::World world(scene);          // scene checked with tumble::validate first
///   for (int i = 0; i < 300; ++i) world.step();
///   world.apply_impulse(0, {0, 5, 0}, world.body(0).s.x);
///
/// Not thread-safe: one thread owns a World (the server's simulation thread); with
/// set_threads it lends each step to worker threads of its own. No I/O, no
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

/// Contact and sleep data kept between steps (engine/src/pipeline.hpp).
struct ContactCache;
/// Broad-phase acceleration kept between steps; never changes a result.
struct BroadPhaseCache;
/// Per-step buffers of the stages.
struct StepScratch;
/// What a step keeps to take a pass again (WorldDef::max_overlap).
struct PassSnapshot;
/// Worker threads of the stages.
class WorkerPool;

/// Thrown by World's entry points for input that names no body or is not finite.
struct InvalidInput : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

/// A simulated world. Deterministic: the same scene and calls give bit-identical states.
/// Stands for the floor in ContactView::a.
inline constexpr std::uint32_t kFloorBody = 0xFFFFFFFFu;

/// One contact point as the last step left it, for viewers and tools.
struct ContactView {
  Vec3 position = Vec3::Zero();  ///< World, m.
  Vec3 normal = Vec3::UnitY();   ///< Unit, world, from body a (or the floor) to body b.
  double impulse = 0.0;  ///< Normal impulse over the last step, N·s (≥ 0); see `solved`.
  std::uint32_t a = kFloorBody;  ///< Body index, or kFloorBody.
  std::uint32_t b = 0;           ///< Body index.
  bool solved = true;  ///< From the contact solver; false: a body resting alone on the floor,
                       ///< whose impulse is its weight's share m|g|dt / (its touching points).
};

class World {
 public:
  /// Builds the world; throws InvalidInput with the field when validate(scene) fails.
  explicit World(Scene scene);
  /// Deep copies (the contact cache included; broad-phase acceleration and scratch start
  /// empty, which changes no result) and moves.
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

  /// Measures each stage's wall time into last_step().stage_ns, and the contact solve's
  /// passes into last_step().solve_pass_ns, from the next step on. Off by default: the two
  /// clock reads per stage cost about 0.5 µs a step on this project's machines, more than a
  /// lone body's whole step.
  void set_stage_timing(bool on);

  /// Shares each step's independent work (bodies, pairs, contacts of one colour) among
  /// `threads` threads, this one included; 0: one per core. Results are bit-identical for any
  /// count. A new World steps on its owner's thread alone (1); a copy keeps the count.
  void set_threads(unsigned threads);
  /// Threads a step uses (≥ 1).
  unsigned threads() const;
  /// Cores of this machine (std::thread::hardware_concurrency, at least 1).
  static unsigned hardware_threads();

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
  /// The contact points of the last step (cleared first): the solved contacts of touching
  /// bodies (points within 0.1 mm or pushing), then the floor points of every other body that
  /// touches the floor (within 1e-6 m). O(bodies); allocates a flag per body and grows `out`.
  void contacts(std::vector<ContactView>& out) const;
  /// Adds a body (awake) to the running world and returns its id (the next index); time, steps
  /// and every other body's state are kept, and the same additions give the same results.
  /// Throws InvalidInput naming the field ("bodies[12].mass: …") for an invalid or duplicate
  /// definition, or past kMaxBodies.
  BodyId add_body(const BodyDef& def);

 private:
  /// Builds the broad phase's cache (boxes of the sleeping bodies, sweep order).
  void prime_broad_phase();
  /// One pass of the stages over dt; its counters into `stats`. With `keep`, what the pass
  /// changes after its contacts are found is kept there first (take_snapshot).
  void pass(double dt, StepStats& stats, PassSnapshot* keep);
  /// Keeps the awake bodies, the contact cache and the pass count, if the pass has pairs.
  void take_snapshot(PassSnapshot& keep) const;
  /// The step over dt in passes that keep max_overlap (world_step.cpp says how many).
  void step_within_overlap(double dt);
  /// A pass over dt, taken again as two halves while it opens an overlap deeper than
  /// max_overlap (`halvings`: how often the step's dt was halved already).
  void step_passes(double dt, int halvings);

  Scene scene_;
  std::vector<Body> bodies_;
  double time_ = 0.0;
  std::uint64_t steps_ = 0;
  std::uint64_t passes_ = 0;  // passes of the stages run (steps_ unless some were halved)
  int halvings_ = 0;          // max_overlap: how often the next step starts halved
  int finest_ = 0;            // max_overlap: the most halvings a pass of this step took
  std::uint64_t total_impacts_ = 0;
  std::size_t unequal_moments_ = 0;  // bodies that are not cubes (whose flight may use lanes)
  StepStats last_;
  bool time_stages_ = false;
  std::unique_ptr<ContactCache> cache_;       // warm-start contacts, sleeping islands
  std::unique_ptr<BroadPhaseCache> broad_;   // sweep orders, fat boxes (acceleration only)
  std::unique_ptr<StepScratch> scratch_;     // per-step buffers
  std::unique_ptr<WorkerPool> pool_;         // threads of the stages (never copied)
  std::unique_ptr<PassSnapshot> snapshot_;   // for max_overlap, made at its first use
};

}  // namespace tumble
