/// Box3D peer: the soft-step solver with graph colouring and SIMD (float32), built by hand
/// beside Tumble (it has no Debian package; bench/README.md says how) and found at configure
/// time through TUMBLE_BOX3D_ROOT. One worker, Box3D's documented four substeps a step.
#include <box3d/box3d.h>
#include <box3d/collision.h>

#include <string>
#include <vector>

#include "peers/peer.hpp"

namespace tumble_bench {
namespace {

b3Vec3 to_b3(const Vec3& v) {
  return {static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())};
}
Vec3 from_b3(const b3Vec3& v) { return {v.x, v.y, v.z}; }

// Box3D's own recommendation for b3World_Step ("usually 4").
constexpr int kSubSteps = 4;
// Half extents of the ground box (m): its top face is the plane y = 0, wider than any scene.
constexpr float kGroundHalfWidth = 2000.0f;

class Box3dWorld final : public PeerWorld {
 public:
  explicit Box3dWorld(const PeerScene& scene) : dt_(static_cast<float>(scene.dt)) {
    b3WorldDef def = b3DefaultWorldDef();
    def.gravity = to_b3(scene.gravity);
    def.enableSleep = scene.allow_sleep;
    def.workerCount = 1;
    world_ = b3CreateWorld(&def);
    // Box3D mixes friction as √(μa μb) and restitution as max(ea, eb): μ and e on every shape
    // give every box–floor and box–box pair μ and e.
    b3ShapeDef shape = b3DefaultShapeDef();
    shape.baseMaterial.friction = static_cast<float>(scene.friction);
    shape.baseMaterial.restitution = static_cast<float>(scene.restitution);
    if (scene.floor) add_ground(shape);
    bodies_.reserve(scene.boxes.size());
    for (const PeerBox& b : scene.boxes) add_box(b, shape);
  }
  ~Box3dWorld() override { b3DestroyWorld(world_); }
  Box3dWorld(const Box3dWorld&) = delete;
  Box3dWorld& operator=(const Box3dWorld&) = delete;

  void step() override { b3World_Step(world_, dt_, kSubSteps); }

  PeerBodyState state(std::size_t i) const override {
    const b3BodyId id = bodies_[i];
    const b3Quat q = b3Body_GetRotation(id);
    PeerBodyState s;
    s.position = from_b3(b3Body_GetPosition(id));
    s.orientation = Quat(q.s, q.v.x, q.v.y, q.v.z);
    s.velocity = from_b3(b3Body_GetLinearVelocity(id));
    s.angular_velocity = from_b3(b3Body_GetAngularVelocity(id));
    return s;
  }

  long awake_count() const override { return b3World_GetAwakeBodyCount(world_); }

 private:
  void add_ground(const b3ShapeDef& shape) {
    b3BodyDef def = b3DefaultBodyDef();
    def.position = {0.0f, -1.0f, 0.0f};
    const b3BodyId ground = b3CreateBody(world_, &def);
    const b3BoxHull box = b3MakeBoxHull(kGroundHalfWidth, 1.0f, kGroundHalfWidth);
    b3CreateHullShape(ground, &shape, &box.base);
  }

  void add_box(const PeerBox& b, b3ShapeDef shape) {
    b3BodyDef def = b3DefaultBodyDef();
    def.type = b3_dynamicBody;
    def.position = to_b3(b.position);
    def.rotation = {to_b3(b.orientation.vec()), static_cast<float>(b.orientation.w())};
    def.linearVelocity = to_b3(b.velocity);
    def.angularVelocity = to_b3(b.angular_velocity);
    const b3BodyId id = b3CreateBody(world_, &def);
    const Vec3 half = 0.5 * b.size;
    const b3BoxHull box = b3MakeBoxHull(static_cast<float>(half.x()),
                                        static_cast<float>(half.y()),
                                        static_cast<float>(half.z()));
    shape.density = static_cast<float>(b.mass / b.size.prod());  // Box3D takes kg/m³
    b3CreateHullShape(id, &shape, &box.base);
    bodies_.push_back(id);
  }

  float dt_;
  b3WorldId world_;
  std::vector<b3BodyId> bodies_;
};

}  // namespace

PeerEngine box3d_peer() {
  const b3Version v = b3GetVersion();
  return {"box3d",
          std::to_string(v.major) + "." + std::to_string(v.minor) + "." +
              std::to_string(v.revision),
          "b3World_Step(dt, 4): four substeps of the soft-step solver (graph colouring, SSE2, "
          "float32), one worker; the ground a static 4 km box whose top is the floor; friction "
          "μ and restitution e on every shape (Box3D mixes them as √(μa μb) and max(ea, eb), "
          "so every pair gets μ and e; no bounce below its 1 m/s restitution threshold); "
          "default sleeping (enableSleep off when a run must stay awake), contact softness and "
          "speculative distance",
          [](const PeerScene& s) { return std::make_unique<Box3dWorld>(s); }};
}

}  // namespace tumble_bench
