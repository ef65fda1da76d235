#pragma once
/// A small common interface over the peer engines (Bullet, ODE, MuJoCo; Box3D when built
/// beside) so every benchmark writes the same scene into each of them. World frame as in Tumble: y up, floor y = 0.
/// Not thread-safe: one thread owns a PeerWorld.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace tumble_bench {

using Vec3 = Eigen::Vector3d;     ///< Vectors in the world frame.
using Quat = Eigen::Quaterniond;  ///< Orientations, body → world.

/// One box as a peer sees it (SI units, angular velocity in the world frame).
struct PeerBox {
  Vec3 size{1.0, 1.0, 1.0};            ///< Full edge lengths, m.
  double mass = 1.0;                   ///< kg.
  Vec3 position = Vec3::Zero();        ///< Centre of mass, m.
  Quat orientation = Quat::Identity(); ///< Body → world.
  Vec3 velocity = Vec3::Zero();        ///< m/s.
  Vec3 angular_velocity = Vec3::Zero();///< rad/s, world frame.
};

/// A scene for a peer: boxes, an optional floor y = 0, gravity, fixed step.
struct PeerScene {
  Vec3 gravity{0.0, -9.81, 0.0};  ///< m/s².
  bool floor = true;              ///< Plane y = 0.
  double restitution = 0.0;       ///< e against the floor.
  double friction = 0.0;          ///< Coulomb μ against the floor.
  double dt = 1.0 / 240.0;        ///< Step, s.
  bool allow_sleep = true;        ///< Let the peer deactivate still bodies (its default).
  /// Bodies rest on each other (stacks, piles): peers add their documented stacking settings
  /// and room for body–body contacts. Separated scenes leave it false.
  bool stacking = false;
  std::vector<PeerBox> boxes;     ///< Bodies.
};

/// Pose and velocity of one body read back from a peer.
struct PeerBodyState {
  Vec3 position = Vec3::Zero();        ///< m.
  Quat orientation = Quat::Identity(); ///< Body → world.
  Vec3 velocity = Vec3::Zero();        ///< m/s.
  Vec3 angular_velocity = Vec3::Zero();///< rad/s, world frame.
};

/// A live peer world.
class PeerWorld {
 public:
  virtual ~PeerWorld() = default;  ///< Frees the peer's world.
  /// Advances by the scene's dt.
  virtual void step() = 0;
  /// State of body i.
  virtual PeerBodyState state(std::size_t i) const = 0;
  /// Bodies the peer currently simulates (not deactivated), or -1 if it cannot say.
  virtual long awake_count() const { return -1; }
  /// Impacts resolved since the world was built (floor and body–body), or -1 when the engine
  /// has no such counter (no peer has one: they resolve contacts, not impacts).
  virtual long long impacts() const { return -1; }
  /// Called before each step of a run that must keep every body awake (`step` counts from 1).
  /// Peers are built with sleeping off for such runs (PeerScene::allow_sleep) and do nothing
  /// here; Tumble, which has no such switch, wakes its bodies.
  virtual void keep_awake(long /*step*/) {}
  /// What went wrong so far in a way that changes the simulation (a full contact buffer …),
  /// empty when nothing did.
  virtual std::string trouble() const { return {}; }
  /// Steps run on the calling thread alone since the world was built, because its threads
  /// were held up (Tumble on several threads on a busy machine), or -1 when the engine has no
  /// such count.
  virtual long steps_alone() const { return -1; }
};

/// A peer engine: its name, what we set, and a factory.
struct PeerEngine {
  std::string name;      ///< "bullet", "ode", "mujoco".
  std::string version;   ///< Library version as reported or packaged.
  std::string settings;  ///< The settings we chose, in words (for the docs).
  std::function<std::unique_ptr<PeerWorld>(const PeerScene&)> make;  ///< Builds a world.
};

/// The peers this binary was built with (those found at configure time).
std::vector<PeerEngine> available_peers();

#ifdef TUMBLE_BENCH_HAVE_BULLET
PeerEngine bullet_peer();  ///< Bullet (double precision build).
#endif
#ifdef TUMBLE_BENCH_HAVE_ODE
PeerEngine ode_peer();  ///< Open Dynamics Engine.
#endif
#ifdef TUMBLE_BENCH_HAVE_MUJOCO
PeerEngine mujoco_peer(bool rk4);  ///< MuJoCo with Euler (default) or RK4.
#endif
#ifdef TUMBLE_BENCH_HAVE_BOX3D
PeerEngine box3d_peer();  ///< Box3D, built by hand beside Tumble (TUMBLE_BOX3D_ROOT).
#endif

}  // namespace tumble_bench
