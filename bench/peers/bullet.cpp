/// Bullet peer: btDiscreteDynamicsWorld, double-precision build (bullet-float64), one fixed
/// substep per step, implicit body-frame gyroscopic term, restitution as Bullet multiplies it.
#include <btBulletDynamicsCommon.h>

#include <cmath>

#include "peers/peer.hpp"

namespace tumble_bench {
namespace {

btVector3 to_bt(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
Vec3 from_bt(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

class BulletWorld final : public PeerWorld {
 public:
  explicit BulletWorld(const PeerScene& scene) : dt_(scene.dt) {
    world_.setGravity(to_bt(scene.gravity));
    if (scene.floor) {
      floor_shape_ = std::make_unique<btStaticPlaneShape>(btVector3(0, 1, 0), 0);
      btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, floor_shape_.get());
      // Bullet combines restitution and friction as products of the two bodies' values: with
      // √e and √μ on every body and on the plane, box–plane and box–box pairs both get e, μ.
      info.m_restitution = std::sqrt(scene.restitution);
      info.m_friction = std::sqrt(scene.friction);
      floor_ = std::make_unique<btRigidBody>(info);
      world_.addRigidBody(floor_.get());
    }
    bodies_.reserve(scene.boxes.size());
    for (const PeerBox& b : scene.boxes) {
      shapes_.push_back(std::make_unique<btBoxShape>(to_bt(b.size * 0.5)));
      btVector3 inertia(0, 0, 0);
      shapes_.back()->calculateLocalInertia(b.mass, inertia);
      btTransform t;
      t.setOrigin(to_bt(b.position));
      t.setRotation(btQuaternion(b.orientation.x(), b.orientation.y(), b.orientation.z(),
                                 b.orientation.w()));
      btRigidBody::btRigidBodyConstructionInfo info(b.mass, nullptr, shapes_.back().get(),
                                                     inertia);
      info.m_startWorldTransform = t;
      info.m_restitution = std::sqrt(scene.restitution);
      info.m_friction = std::sqrt(scene.friction);
      auto body = std::make_unique<btRigidBody>(info);
      body->setLinearVelocity(to_bt(b.velocity));
      body->setAngularVelocity(to_bt(b.angular_velocity));
      body->setFlags(body->getFlags() | BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY);
      if (!scene.allow_sleep) body->setActivationState(DISABLE_DEACTIVATION);
      world_.addRigidBody(body.get());
      bodies_.push_back(std::move(body));
    }
  }
  ~BulletWorld() override {
    for (auto& b : bodies_) world_.removeRigidBody(b.get());
    if (floor_) world_.removeRigidBody(floor_.get());
  }

  void step() override { world_.stepSimulation(dt_, 1, dt_); }

  PeerBodyState state(std::size_t i) const override {
    const btRigidBody& b = *bodies_[i];
    const btTransform& t = b.getCenterOfMassTransform();
    const btQuaternion q = t.getRotation();
    PeerBodyState s;
    s.position = from_bt(t.getOrigin());
    s.orientation = Quat(q.w(), q.x(), q.y(), q.z());
    s.velocity = from_bt(b.getLinearVelocity());
    s.angular_velocity = from_bt(b.getAngularVelocity());
    return s;
  }

  long awake_count() const override {
    long n = 0;
    for (const auto& b : bodies_) n += b->isActive() ? 1 : 0;
    return n;
  }

 private:
  double dt_;
  btDefaultCollisionConfiguration config_;
  btCollisionDispatcher dispatcher_{&config_};
  btDbvtBroadphase broadphase_;
  btSequentialImpulseConstraintSolver solver_;
  btDiscreteDynamicsWorld world_{&dispatcher_, &broadphase_, &solver_, &config_};
  std::unique_ptr<btCollisionShape> floor_shape_;
  std::unique_ptr<btRigidBody> floor_;
  std::vector<std::unique_ptr<btBoxShape>> shapes_;
  std::vector<std::unique_ptr<btRigidBody>> bodies_;
};

}  // namespace

PeerEngine bullet_peer() {
  return {"bullet", std::to_string(btGetVersion() / 100) + "." + std::to_string(btGetVersion() % 100),
          "btDiscreteDynamicsWorld + btDbvtBroadphase + sequential-impulse solver (10 iterations, "
          "default), double precision; stepSimulation(dt, 1, dt) (one fixed substep); "
          "BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY; restitution √e on every box and on the "
          "plane (Bullet multiplies the two values of a pair, so box–plane and box–box pairs "
          "both get e), friction √μ likewise; default deactivation (sleeping after 2 s below "
          "0.8 m/s and 1 rad/s; DISABLE_DEACTIVATION when a run must stay awake) and default "
          "0.04 m collision margin",
          [](const PeerScene& s) { return std::make_unique<BulletWorld>(s); }};
}

}  // namespace tumble_bench
