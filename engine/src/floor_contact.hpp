#pragma once
/// Bodies against the floor plane y = h: a lone body's step with its impacts at their time
/// and its resting contact (floor_contact.cpp; the time of impact, the impulses and the
/// vertices' geometry in floor_time_of_impact, floor_impulse and floor_geometry).
/// Pure functions over one body; thread-safe.
#include "floor_geometry.hpp"  // lowest_vertex_y
#include "integrators.hpp"
#include "tumble/body.hpp"
#include "tumble/scene.hpp"

namespace tumble {

/// What one body's step cost and met.
struct FloorStepResult {
  int impacts = 0;         ///< Impacts resolved (several may fall in one step).
  int toi_iterations = 0;  ///< Partial-step evaluations spent locating them.
  bool touched = false;    ///< The body was in contact with the floor at some point.
};

/// Speed below which an impact rebounds with e = 0 and contact becomes resting contact
/// (m/s): half the speed gravity adds in one step, so a bounce shorter than about one step
/// ends the Zeno series. Perfectly elastic bodies (e = 1) keep bouncing down to 1e-6 m/s.
double rest_speed(double restitution, const Vec3& gravity, double dt);

/// True when the body is still (P = L = 0) with a whole face on the floor (three or more
/// vertices within 1e-9 m of it, none below) and the floor holds it there against `gravity`
/// (m/s²): statically at rest, so it may start asleep.
bool rests_on_face(const BodyState& s, const BodyConstants& c, double floor_height,
                   const Vec3& gravity);

/// True when the body is still (P = L = 0 to 1e-12) with three or more vertices within the
/// resting contact's band (1e-6 m) of the floor: how a landed box comes to rest on a face.
bool at_rest_on_face(const BodyState& s, const BodyConstants& c, double floor_height);

/// True when the body's lowest points on the floor are one or two vertices (a corner or an
/// edge within the resting contact's 1e-6 m band), not a face: under gravity into the floor a
/// box so supported balances at best unstably.
bool touches_floor_on_edge_or_corner(const BodyState& s, const BodyConstants& c,
                                     double floor_height);

/// Advances one awake body by dt: flight with the world's integrator, impacts located by
/// the world's TOI method and answered with impulses, resting contact without sinking.
/// `spin` (may be null) keeps a cube's turn between steps (integrators.hpp).
FloorStepResult advance_with_floor(Body& body, const WorldDef& world, double dt,
                                   SpinCache* spin = nullptr);

/// The same for a body under `exact` whose torque-free attitude after dt, `rotated`, was
/// computed beforehand (free_rotation_exact_many): its flights over the whole step take it
/// (integrators.hpp, `advance_turned`). The same bits as without it.
FloorStepResult advance_with_floor(Body& body, const WorldDef& world, double dt,
                                   SpinCache* spin, const Mat3& rotated);

/// Applies simultaneous impulses at the vertices touching the floor (within 1e-9 m of the
/// lowest) so that no contact approaches: restitution e, Coulomb friction μ. Returns the
/// number of vertices that received an impulse.
int resolve_floor_impact(BodyState& s, const BodyConstants& c, double floor_height,
                         double restitution, double friction, double rest_speed_ms);

}  // namespace tumble
