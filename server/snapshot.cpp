#include "snapshot.hpp"

#include <algorithm>

#include "tumble/scene_io.hpp"

namespace tumble::server {
namespace {

nlohmann::json vec_json(const Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); }

}  // namespace

std::shared_ptr<const SceneInfo> make_scene_info(std::uint64_t generation, const Scene& scene,
                                                 std::vector<BodyConstants> constants) {
  auto info = std::make_shared<SceneInfo>();
  info->generation = generation;
  info->scene = scene;
  info->constants = std::move(constants);
  nlohmann::json bodies = nlohmann::json::array();
  for (const BodyDef& b : scene.bodies)
    bodies.push_back({{"name", b.name}, {"size", vec_json(b.size)}, {"color", b.color}});
  const nlohmann::json message = {{"type", "scene"},
                                  {"scene", scene_to_json(scene)},
                                  {"faces", kBoxFaces},
                                  {"bodies", std::move(bodies)}};
  info->message = std::make_shared<const std::string>(message.dump());
  return info;
}

double frame_time(const Snapshot& s, Clock::time_point at) {
  if (s.paused || !s.previous_bodies) return s.time;
  const double ahead = std::chrono::duration<double>(s.wall_time - at).count();
  return std::clamp(s.time - s.speed * ahead, s.previous_time, s.time);
}

nlohmann::json scene_json(const Snapshot& s) {
  Scene scene = s.scene->scene;
  scene.world.integrator = s.integrator;
  return scene_to_json(scene);
}

nlohmann::json state_json(const Snapshot& s) {
  nlohmann::json bodies = nlohmann::json::array();
  const auto& defs = s.scene->scene.bodies;
  for (std::size_t i = 0; i < s.bodies->size(); ++i) {
    const BodyPose& p = (*s.bodies)[i];
    Quat q(p.rotation);
    q.normalize();
    bodies.push_back({{"name", i < defs.size() ? defs[i].name : std::string()},
                      {"position", vec_json(p.position)},
                      {"orientation", {q.w(), q.x(), q.y(), q.z()}},
                      {"velocity", vec_json(p.velocity)},
                      {"angular_velocity", vec_json(p.angular_velocity)},
                      {"asleep", p.activity == Activity::asleep},
                      {"frozen", p.activity == Activity::frozen}});
  }
  return {{"time", s.time},
          {"step", s.step},
          {"paused", s.paused},
          {"speed", s.speed},
          {"live", s.live},
          {"playing", s.playing},
          {"real_time_factor", s.real_time_factor},
          {"energy", s.energy},
          {"integrator", std::string(to_string(s.integrator))},
          {"bodies", std::move(bodies)}};
}

}  // namespace tumble::server
