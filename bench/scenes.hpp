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

/// N separated unit cubes (1 kg) dropped from 1–3 m (centre height) with random orientation
/// and spin up to 3 rad/s per axis (fixed seed) onto a floor with μ = 1 and e = 0; dt = 1/240 s,
/// `exact`, TOI `root`. A 3 m grid: a cube that lands tilted can roll or slide a little with
/// friction, and its neighbours are 3 m away (centres ≥ 1.73 m apart never touch), so the boxes
/// meet only the floor. The `landing` variant of throughput and peers.
tumble::Scene landing_cubes(std::size_t n, unsigned seed = 42);

/// `resting` unit cubes placed on the floor at rest plus `falling` ones dropped from 2 m with
/// spin, all separated; frictionless floor with e = 0.5, dt = 1/60 s.
tumble::Scene resting_and_falling(std::size_t resting, std::size_t falling);

/// One box, no gravity, no floor (for free-rotation stress tests).
tumble::Scene free_spin(const tumble::Vec3& size, double mass,
                        const tumble::Vec3& angular_velocity, double dt);

/// The scene in the peers' common form (floor moved to y = 0 if it was elsewhere).
PeerScene to_peer(const tumble::Scene& s);

}  // namespace tumble_bench
