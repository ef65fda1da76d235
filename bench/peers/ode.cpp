/// ODE peer: dWorldQuickStep, gyroscopic mode on, contacts with dContactBounce.
#include <ode/ode.h>

#include <mutex>

#include "peers/peer.hpp"

namespace tumble_bench {
namespace {

constexpr int kMaxContacts = 4;      // box–plane: at most 4 corners touch
constexpr int kMaxBodyContacts = 8;  // box–box: dBoxBox returns up to 8 points

class OdeWorld final : public PeerWorld {
 public:
  explicit OdeWorld(const PeerScene& scene)
      : dt_(scene.dt), restitution_(scene.restitution), friction_(scene.friction) {
    static std::once_flag init;
    std::call_once(init, [] { dInitODE2(0); });
    world_ = dWorldCreate();
    space_ = dHashSpaceCreate(nullptr);
    contacts_ = dJointGroupCreate(0);
    dWorldSetGravity(world_, scene.gravity.x(), scene.gravity.y(), scene.gravity.z());
    // The ODE manual recommends a small surface layer against jitter.
    dWorldSetContactSurfaceLayer(world_, 0.001);
    dWorldSetAutoDisableFlag(world_, scene.allow_sleep ? 1 : 0);
    if (scene.stacking) {
      // Stacks: the settings of ODE's own box-stacking demo (demo_boxstack) and the manual's
      // advice against jitter — a little global CFM (softer, better conditioned contacts) and
      // a cap on the velocity the ERP correction may add to push boxes apart.
      dWorldSetCFM(world_, 1e-5);
      dWorldSetContactMaxCorrectingVel(world_, 0.1);
      dWorldSetAutoDisableAverageSamplesCount(world_, 10);
    }
    if (scene.floor) dCreatePlane(space_, 0, 1, 0, 0);
    for (const PeerBox& b : scene.boxes) {
      dBodyID body = dBodyCreate(world_);
      dMass m;
      dMassSetBoxTotal(&m, b.mass, b.size.x(), b.size.y(), b.size.z());
      dBodySetMass(body, &m);
      dBodySetPosition(body, b.position.x(), b.position.y(), b.position.z());
      const dQuaternion q{b.orientation.w(), b.orientation.x(), b.orientation.y(),
                          b.orientation.z()};
      dBodySetQuaternion(body, q);
      dBodySetLinearVel(body, b.velocity.x(), b.velocity.y(), b.velocity.z());
      dBodySetAngularVel(body, b.angular_velocity.x(), b.angular_velocity.y(),
                         b.angular_velocity.z());
      dBodySetGyroscopicMode(body, 1);
      dGeomID geom = dCreateBox(space_, b.size.x(), b.size.y(), b.size.z());
      dGeomSetBody(geom, body);
      bodies_.push_back(body);
    }
  }
  ~OdeWorld() override {
    dJointGroupDestroy(contacts_);
    dSpaceDestroy(space_);
    dWorldDestroy(world_);
  }

  void step() override {
    dSpaceCollide(space_, this, &OdeWorld::near_callback);
    dWorldQuickStep(world_, dt_);
    dJointGroupEmpty(contacts_);
  }

  PeerBodyState state(std::size_t i) const override {
    dBodyID b = bodies_[i];
    const dReal* p = dBodyGetPosition(b);
    const dReal* q = dBodyGetQuaternion(b);
    const dReal* v = dBodyGetLinearVel(b);
    const dReal* w = dBodyGetAngularVel(b);
    PeerBodyState s;
    s.position = {p[0], p[1], p[2]};
    s.orientation = Quat(q[0], q[1], q[2], q[3]);
    s.velocity = {v[0], v[1], v[2]};
    s.angular_velocity = {w[0], w[1], w[2]};
    return s;
  }

  long awake_count() const override {
    long n = 0;
    for (dBodyID b : bodies_) n += dBodyIsEnabled(b) ? 1 : 0;
    return n;
  }

 private:
  static void near_callback(void* data, dGeomID a, dGeomID b) {
    auto* self = static_cast<OdeWorld*>(data);
    dBodyID ba = dGeomGetBody(a);
    dBodyID bb = dGeomGetBody(b);
    if (ba && bb && dAreConnectedExcluding(ba, bb, dJointTypeContact)) return;
    // Body pairs too (stacks, piles): up to 8 points for two boxes, 4 for a box on the plane.
    const int max_contacts = (ba && bb) ? kMaxBodyContacts : kMaxContacts;
    dContact contact[kMaxBodyContacts];
    for (dContact& c : contact) {
      c.surface.mode = dContactBounce;
      c.surface.mu = self->friction_;
      c.surface.bounce = self->restitution_;
      c.surface.bounce_vel = 0.01;
    }
    const int n = dCollide(a, b, max_contacts, &contact[0].geom, sizeof(dContact));
    for (int i = 0; i < n; ++i) {
      dJointID j = dJointCreateContact(self->world_, self->contacts_, &contact[i]);
      dJointAttach(j, ba, bb);
    }
  }

  double dt_;
  double restitution_;
  double friction_;
  dWorldID world_;
  dSpaceID space_;
  dJointGroupID contacts_;
  std::vector<dBodyID> bodies_;
};

}  // namespace

PeerEngine ode_peer() {
  return {"ode", dODE_VERSION,
          "dWorldQuickStep (20 iterations, default), dHashSpace, plane + box geoms, up to 4 "
          "contacts per pair, dContactBounce with bounce = e and bounce_vel = 0.01 m/s, mu = μ, "
          "dBodySetGyroscopicMode(1), contact surface layer 1 mm, auto-disable on when the "
          "scene allows sleeping; default ERP 0.2 / CFM 1e-10 (double). Body–body contacts "
          "through dCollide (up to 8 points per box pair) into the same contact joint group, "
          "same mu and bounce. Stacking scenes (tower, pyramid, pile) add what ODE's "
          "demo_boxstack and manual recommend: global CFM 1e-5, "
          "dWorldSetContactMaxCorrectingVel 0.1 m/s, auto-disable averaged over 10 samples",
          [](const PeerScene& s) { return std::make_unique<OdeWorld>(s); }};
}

}  // namespace tumble_bench
