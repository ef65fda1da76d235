#pragma once
/// A scene: world settings and body definitions, as read from scenes/*.json.
/// Plain data; validation names the offending field.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tumble/body.hpp"

namespace tumble {

/// Flight integrators; every one advances the same state (x, R, P, L).
enum class Integrator {
  euler,             ///< Explicit Euler (order 1), R re-orthonormalised.
  midpoint,          ///< The seed's: Euler half step, derivative at the midpoint (order 2).
  rk4,               ///< Classic Runge–Kutta 4, R re-orthonormalised.
  symplectic_euler,  ///< Velocity first, then x += v h, R ← exp(h ω̂) R.
  splitting,         ///< Exact ballistic translation + symmetric free-rotation splitting.
  exact,             ///< Closed-form flight (cube / symmetric / elliptic general box).
};

/// Time-of-impact search against the floor.
enum class ToiMethod {
  bisection,  ///< The seed's: halve the step until the interval is below the tolerance.
  root,       ///< TOMS 748 bracketing on the trajectory's lowest-vertex height.
};

/// All integrators, in a stable order (for menus and sweeps).
inline constexpr Integrator kIntegrators[] = {Integrator::euler, Integrator::midpoint,
                                              Integrator::rk4, Integrator::symplectic_euler,
                                              Integrator::splitting, Integrator::exact};

/// Name of an integrator as written in scenes ("rk4" …).
std::string_view to_string(Integrator i);
/// Name of a TOI method ("bisection", "root").
std::string_view to_string(ToiMethod m);
/// Parses an integrator name; nullopt when unknown.
std::optional<Integrator> parse_integrator(std::string_view name);
/// Parses a TOI method name; nullopt when unknown.
std::optional<ToiMethod> parse_toi_method(std::string_view name);

/// The floor: the plane y = height.
struct Floor {
  double height = 0.0;       ///< m.
  double restitution = 1.0;  ///< e, in [0, 1].
  double friction = 0.0;     ///< Coulomb μ, ≥ 0.
};

/// World-wide settings of a scene.
struct WorldDef {
  std::string name = "untitled";              ///< Scene name.
  std::string description;                    ///< What the scene shows (≤ 4 KiB; "" for none).
  Vec3 gravity{0.0, -9.81, 0.0};              ///< m/s².
  std::optional<Floor> floor = Floor{};       ///< nullopt: no floor.
  double dt = 1.0 / 60.0;                     ///< Physics step, s.
  Integrator integrator = Integrator::exact;  ///< Flight integrator.
  ToiMethod toi = ToiMethod::root;            ///< Impact-time search.
  double toi_tolerance = 1e-9;                ///< Impact-time tolerance, s.
  /// Deepest overlap a step may open between two boxes or a box and the floor, m (0: off, else
  /// at least kMinMaxOverlap); a step that opens a deeper one is taken again as two halves,
  /// down to dt / 2^kMaxHalvings.
  double max_overlap = 0.0;
};

/// Least WorldDef::max_overlap other than 0, m: five times the 0.2 mm a resting contact may
/// overlap (the contact solver leaves that much alone), so that boxes coming to rest do not
/// keep a step halving.
inline constexpr double kMinMaxOverlap = 1e-3;

/// Most times World::step halves a pass to keep WorldDef::max_overlap (a step is then at
/// most 2^(kMaxHalvings+1) − 1 passes).
inline constexpr int kMaxHalvings = 5;

/// A whole scene.
struct Scene {
  WorldDef world;              ///< Settings.
  std::vector<BodyDef> bodies; ///< Bodies, in order (their index is their id).
};

/// Most bodies a scene may hold.
inline constexpr std::size_t kMaxBodies = 100000;

/// A rejected scene: which field ("bodies[2].mass") and why.
struct SceneError {
  std::string field;    ///< JSON-path-like field name.
  std::string message;  ///< Human-readable reason.
};

/// Checks physical validity (positive mass and size, finite values, e ∈ [0,1] …).
std::optional<SceneError> validate(const Scene& scene);

/// Checks one body as validate does; its fields are named under `at` ("bodies[3]").
std::optional<SceneError> validate_body(const BodyDef& body, const std::string& at);

}  // namespace tumble
