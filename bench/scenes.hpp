#pragma once
/// Scenes of the benchmarks: the bundled scenes/*.json where they exist (through
/// tumble::load_scene), synthetic ones built here otherwise, and their translation into the
/// peers' common description. Pure functions; thread-safe.
#include <cstddef>
#include <string>

#include "peers/peer.hpp"
#include "tumble/scene.hpp"

namespace tumble_bench {

/// A bundled scene by name ("tumble", "bounce", "seed" …).
tumble::Scene bundled(const std::string& name);

/// The same scene with another integrator, TOI method and step.
tumble::Scene with(tumble::Scene s, tumble::Integrator integrator, tumble::ToiMethod toi,
                   double dt);

/// Shape of the bodies of separated_boxes: cubes (one edge length each; Tumble turns them in
/// closed form) or general boxes (three edge lengths; `exact` runs Jacobi elliptic functions).
enum class BoxShape { cube, general };

/// "cube" / "box".
const char* to_string(BoxShape shape);

/// N well-separated boxes (random size 0.2–0.6 m per edge, or one edge for cubes; mass
/// 1–10 kg, pose, spin up to 3 rad/s, drop height 1–3 m, fixed seed) on a 1.5 m grid over a
/// frictionless floor with e = 0.5. Frictionless: the floor pushes only vertically, so centres
/// never move sideways and the boxes stay separated.
tumble::Scene separated_boxes(std::size_t n, double dt, unsigned seed = 42,
                              BoxShape shape = BoxShape::general);

/// `resting` unit cubes placed on the floor at rest plus `falling` ones dropped from 2 m with
/// spin, all separated; frictionless floor with e = 0.5, dt = 1/60 s.
tumble::Scene resting_and_falling(std::size_t resting, std::size_t falling);

/// One box, no gravity, no floor (for free-rotation stress tests).
tumble::Scene free_spin(const tumble::Vec3& size, double mass,
                        const tumble::Vec3& angular_velocity, double dt);

/// The scene in the peers' common form (floor moved to y = 0 if it was elsewhere).
PeerScene to_peer(const tumble::Scene& s);

}  // namespace tumble_bench
