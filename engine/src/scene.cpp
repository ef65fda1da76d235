#include "tumble/scene.hpp"

#include <cmath>
#include <set>

namespace tumble {
namespace {

constexpr std::string_view kIntegratorNames[] = {"euler",           "midpoint", "rk4",
                                                 "symplectic_euler", "splitting", "exact"};
constexpr std::string_view kToiNames[] = {"bisection", "root"};

bool finite(const Vec3& v) { return all_finite(v); }

bool valid_color(const std::string& c) {
  if (c.size() != 7 || c[0] != '#') return false;
  for (std::size_t i = 1; i < 7; ++i)
    if (!std::isxdigit(static_cast<unsigned char>(c[i]))) return false;
  return true;
}

}  // namespace

std::optional<SceneError> validate_body(const BodyDef& b, const std::string& at) {
  auto err = [&](const char* field, std::string msg) {
    return SceneError{at + "." + field, std::move(msg)};
  };
  if (b.name.empty()) return err("name", "must not be empty");
  if (!finite(b.size) || (b.size.array() <= 0.0).any())
    return err("size", "every edge length must be finite and > 0 m");
  if ((b.size.array() > 1e4).any()) return err("size", "edge lengths above 1e4 m are refused");
  if (!std::isfinite(b.mass) || b.mass <= 0.0) return err("mass", "must be finite and > 0 kg");
  if (b.mass < 1e-9 || b.mass > 1e9) return err("mass", "must be within 1e-9 … 1e9 kg");
  if (!finite(b.position) || (b.position.array().abs() > 1e6).any())
    return err("position", "must be finite and within 1e6 m");
  const Eigen::Vector4d q = b.orientation.coeffs();
  if (!all_finite(q) || q.norm() < 1e-6) return err("orientation", "must be a non-zero finite quaternion");
  if (!finite(b.velocity) || (b.velocity.array().abs() > 1e5).any())
    return err("velocity", "must be finite and within 1e5 m/s");
  if (!finite(b.angular_velocity) || (b.angular_velocity.array().abs() > 1e5).any())
    return err("angular_velocity", "must be finite and within 1e5 rad/s");
  if (b.restitution && !(*b.restitution >= 0.0 && *b.restitution <= 1.0))
    return err("restitution", "must be within [0, 1]");
  if (b.friction && !(*b.friction >= 0.0 && *b.friction <= 10.0))
    return err("friction", "must be within [0, 10]");
  if (!valid_color(b.color)) return err("color", "must be \"#rrggbb\"");
  return std::nullopt;
}

std::string_view to_string(Integrator i) { return kIntegratorNames[static_cast<int>(i)]; }
std::string_view to_string(ToiMethod m) { return kToiNames[static_cast<int>(m)]; }

std::optional<Integrator> parse_integrator(std::string_view name) {
  for (int i = 0; i < 6; ++i)
    if (kIntegratorNames[i] == name) return static_cast<Integrator>(i);
  return std::nullopt;
}

std::optional<ToiMethod> parse_toi_method(std::string_view name) {
  for (int i = 0; i < 2; ++i)
    if (kToiNames[i] == name) return static_cast<ToiMethod>(i);
  return std::nullopt;
}

std::optional<SceneError> validate(const Scene& scene) {
  const WorldDef& w = scene.world;
  if (w.description.size() > 4096) return SceneError{"description", "at most 4096 bytes"};
  if (!finite(w.gravity) || (w.gravity.array().abs() > 1e4).any())
    return SceneError{"gravity", "must be finite and within 1e4 m/s²"};
  if (!std::isfinite(w.dt) || w.dt <= 0.0 || w.dt > 1.0)
    return SceneError{"dt", "must be within (0, 1] s"};
  if (!std::isfinite(w.toi_tolerance) || w.toi_tolerance < 1e-15 || w.toi_tolerance > w.dt)
    return SceneError{"toi_tolerance", "must be within [1e-15 s, dt]"};
  if (!(w.max_overlap == 0.0 || (w.max_overlap >= kMinMaxOverlap && w.max_overlap <= 1.0)))
    return SceneError{"max_overlap",
                      "must be 0 (off) or within [0.001, 1] m (resting contacts themselves overlap "
                      "by up to 0.2 mm)"};
  if (w.floor) {
    if (!std::isfinite(w.floor->height) || std::abs(w.floor->height) > 1e6)
      return SceneError{"floor.height", "must be finite and within 1e6 m"};
    if (!(w.floor->restitution >= 0.0 && w.floor->restitution <= 1.0))
      return SceneError{"floor.restitution", "must be within [0, 1]"};
    if (!(w.floor->friction >= 0.0 && w.floor->friction <= 10.0))
      return SceneError{"floor.friction", "must be within [0, 10]"};
  }
  if (scene.bodies.size() > kMaxBodies)
    return SceneError{"bodies", "at most " + std::to_string(kMaxBodies) + " bodies"};
  std::set<std::string> names;
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const std::string at = "bodies[" + std::to_string(i) + "]";
    if (auto e = validate_body(scene.bodies[i], at)) return e;
    if (!names.insert(scene.bodies[i].name).second)
      return SceneError{at + ".name", "duplicate body name \"" + scene.bodies[i].name + "\""};
  }
  return std::nullopt;
}

}  // namespace tumble
