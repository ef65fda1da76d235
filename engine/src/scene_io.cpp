#include "tumble/scene_io.hpp"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <set>

namespace tumble {
namespace {

using nlohmann::json;

[[noreturn]] void fail(const std::string& field, const std::string& message) {
  throw SceneParseError(field, field.empty() ? message : field + ": " + message);
}

double number(const json& j, const std::string& field) {
  if (!j.is_number()) fail(field, "must be a number");
  return j.get<double>();
}

Vec3 vec3(const json& j, const std::string& field) {
  if (!j.is_array() || j.size() != 3) fail(field, "must be an array of 3 numbers");
  return {number(j[0], field + "[0]"), number(j[1], field + "[1]"), number(j[2], field + "[2]")};
}

std::string text(const json& j, const std::string& field) {
  if (!j.is_string()) fail(field, "must be a string");
  return j.get<std::string>();
}

void refuse_unknown_keys(const json& j, const std::string& at,
                         std::initializer_list<const char*> known) {
  for (const auto& item : j.items()) {
    const std::string& key = item.key();
    if (std::none_of(known.begin(), known.end(), [&key](const char* k) { return key == k; }))
      fail(at.empty() ? key : at + "." + key, "unknown field");
  }
}

BodyDef body_from_json(const json& j, const std::string& at) {
  if (!j.is_object()) fail(at, "must be an object");
  refuse_unknown_keys(j, at, {"name", "size", "mass", "position", "orientation", "velocity",
                              "angular_velocity", "restitution", "friction", "color"});
  BodyDef b;
  if (j.contains("name")) b.name = text(j["name"], at + ".name");
  if (j.contains("size")) b.size = vec3(j["size"], at + ".size");
  if (j.contains("mass")) b.mass = number(j["mass"], at + ".mass");
  if (j.contains("position")) b.position = vec3(j["position"], at + ".position");
  if (j.contains("orientation")) {
    const json& q = j["orientation"];
    const std::string f = at + ".orientation";
    if (!q.is_array() || q.size() != 4) fail(f, "must be [w, x, y, z]");
    b.orientation = Quat(number(q[0], f), number(q[1], f), number(q[2], f), number(q[3], f));
  }
  if (j.contains("velocity")) b.velocity = vec3(j["velocity"], at + ".velocity");
  if (j.contains("angular_velocity"))
    b.angular_velocity = vec3(j["angular_velocity"], at + ".angular_velocity");
  if (j.contains("restitution")) b.restitution = number(j["restitution"], at + ".restitution");
  if (j.contains("friction")) b.friction = number(j["friction"], at + ".friction");
  if (j.contains("color")) b.color = text(j["color"], at + ".color");
  return b;
}

}  // namespace

Scene scene_from_json(const json& j) {
  if (!j.is_object()) fail("", "a scene must be a JSON object");
  refuse_unknown_keys(j, "", {"name", "gravity", "floor", "dt", "integrator", "toi",
                              "toi_tolerance", "max_overlap", "bodies", "description"});
  Scene scene;
  WorldDef& w = scene.world;
  if (j.contains("name")) w.name = text(j["name"], "name");
  if (j.contains("description")) w.description = text(j["description"], "description");
  if (j.contains("gravity")) w.gravity = vec3(j["gravity"], "gravity");
  if (j.contains("floor")) {
    const json& f = j["floor"];
    if (f.is_null()) {
      w.floor.reset();
    } else {
      if (!f.is_object()) fail("floor", "must be an object or null");
      refuse_unknown_keys(f, "floor", {"height", "restitution", "friction"});
      Floor floor;
      if (f.contains("height")) floor.height = number(f["height"], "floor.height");
      if (f.contains("restitution")) floor.restitution = number(f["restitution"], "floor.restitution");
      if (f.contains("friction")) floor.friction = number(f["friction"], "floor.friction");
      w.floor = floor;
    }
  }
  if (j.contains("dt")) w.dt = number(j["dt"], "dt");
  if (j.contains("integrator")) {
    const std::string name = text(j["integrator"], "integrator");
    const auto i = parse_integrator(name);
    if (!i) fail("integrator", "unknown integrator \"" + name + "\" (euler, midpoint, rk4, symplectic_euler, splitting, exact)");
    w.integrator = *i;
  }
  if (j.contains("toi")) {
    const std::string name = text(j["toi"], "toi");
    const auto m = parse_toi_method(name);
    if (!m) fail("toi", "unknown method \"" + name + "\" (bisection, root)");
    w.toi = *m;
  }
  if (j.contains("toi_tolerance")) w.toi_tolerance = number(j["toi_tolerance"], "toi_tolerance");
  if (j.contains("max_overlap")) w.max_overlap = number(j["max_overlap"], "max_overlap");
  if (!j.contains("bodies") || !j["bodies"].is_array()) fail("bodies", "must be an array");
  const json& bodies = j["bodies"];
  if (bodies.size() > kMaxBodies)
    fail("bodies", "at most " + std::to_string(kMaxBodies) + " bodies");
  scene.bodies.reserve(bodies.size());
  for (std::size_t i = 0; i < bodies.size(); ++i)
    scene.bodies.push_back(body_from_json(bodies[i], "bodies[" + std::to_string(i) + "]"));
  if (auto error = validate(scene)) fail(error->field, error->message);
  return scene;
}

json scene_to_json(const Scene& scene) {
  const WorldDef& w = scene.world;
  auto arr = [](const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); };
  json j;
  j["name"] = w.name;
  if (!w.description.empty()) j["description"] = w.description;
  j["gravity"] = arr(w.gravity);
  j["floor"] = w.floor ? json{{"height", w.floor->height},
                              {"restitution", w.floor->restitution},
                              {"friction", w.floor->friction}}
                       : json(nullptr);
  j["dt"] = w.dt;
  j["integrator"] = std::string(to_string(w.integrator));
  j["toi"] = std::string(to_string(w.toi));
  j["toi_tolerance"] = w.toi_tolerance;
  if (w.max_overlap > 0.0) j["max_overlap"] = w.max_overlap;
  json bodies = json::array();
  for (const BodyDef& b : scene.bodies) {
    json jb{{"name", b.name},
            {"size", arr(b.size)},
            {"mass", b.mass},
            {"position", arr(b.position)},
            {"orientation", {b.orientation.w(), b.orientation.x(), b.orientation.y(), b.orientation.z()}},
            {"velocity", arr(b.velocity)},
            {"angular_velocity", arr(b.angular_velocity)},
            {"color", b.color}};
    if (b.restitution) jb["restitution"] = *b.restitution;
    if (b.friction) jb["friction"] = *b.friction;
    bodies.push_back(std::move(jb));
  }
  j["bodies"] = std::move(bodies);
  return j;
}

std::filesystem::path bundled_scenes_dir() {
  if (const char* dir = std::getenv("TUMBLE_SCENES_DIR"); dir && *dir) return dir;
  return TUMBLE_SOURCE_SCENES_DIR;
}

std::vector<std::string> bundled_scene_names() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(bundled_scenes_dir(), ec))
    if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

Scene load_scene(const std::string& name_or_path) {
  std::filesystem::path path = name_or_path;
  const auto names = bundled_scene_names();
  if (std::find(names.begin(), names.end(), name_or_path) != names.end())
    path = bundled_scenes_dir() / (name_or_path + ".json");
  std::ifstream in(path);
  if (!in) fail("scene", "no bundled scene or readable file named \"" + name_or_path + "\"");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    fail("", path.string() + ": invalid JSON: " + e.what());
  }
  return scene_from_json(j);
}

}  // namespace tumble
