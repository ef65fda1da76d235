// Scene files: every bundled scene loads; bad scenes are refused naming the field.
#include <algorithm>

#include "world_fixture.hpp"

namespace tumble {
namespace {

using nlohmann::json;

std::string field_of(const std::string& text) {
  try {
    scene_from_json(json::parse(text));
  } catch (const SceneParseError& e) {
    return e.field;
  }
  return "<accepted>";
}

TEST(SceneIo, EveryBundledSceneLoadsAndRoundTrips) {
  const auto names = bundled_scene_names();
  for (const char* expected : {"seed", "bounce", "tumble", "many", "resting", "friction"})
    EXPECT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  for (const auto& name : names) {
    const Scene scene = load_scene(name);
    const Scene again = scene_from_json(scene_to_json(scene));
    EXPECT_EQ(scene_to_json(again), scene_to_json(scene)) << name;
  }
  // The description travels with the scene (the viewer shows it when the scene loads).
  EXPECT_NE(scene_to_json(load_scene("pyramid_large")).value("description", "").find("5050"),
            std::string::npos);
  // The overlap bound travels with a scene that sets it, and a scene without it has none.
  Scene bounded = load_scene("pile");
  EXPECT_EQ(bounded.world.max_overlap, 0.0);
  EXPECT_FALSE(scene_to_json(bounded).contains("max_overlap"));
  bounded.world.max_overlap = 0.01;
  EXPECT_EQ(scene_from_json(scene_to_json(bounded)).world.max_overlap, 0.01);
  const Scene seed = load_scene("seed");
  EXPECT_EQ(seed.world.integrator, Integrator::midpoint);
  EXPECT_EQ(seed.world.toi, ToiMethod::bisection);
  EXPECT_EQ(Scene{}.world.integrator, Integrator::exact);  // the default for new scenes
}

TEST(SceneIo, BadScenesNameTheField) {
  EXPECT_EQ(field_of(R"({"bodies": [{"mass": -1}]})"), "bodies[0].mass");
  EXPECT_EQ(field_of(R"({"bodies": [{"mass": 0}]})"), "bodies[0].mass");
  EXPECT_EQ(field_of(R"({"bodies": [{"size": [1, 0, 1]}]})"), "bodies[0].size");
  EXPECT_EQ(field_of(R"({"bodies": [{"size": [1, 1]}]})"), "bodies[0].size");
  EXPECT_EQ(field_of(R"({"bodies": [{"color": "red"}]})"), "bodies[0].color");
  EXPECT_EQ(field_of(R"({"bodies": [{"orientation": [0,0,0,0]}]})"), "bodies[0].orientation");
  EXPECT_EQ(field_of(R"({"bodies": [{"position": [0, "a", 0]}]})"), "bodies[0].position[1]");
  EXPECT_EQ(field_of(R"({"bodies": [{"restitution": 1.5}]})"), "bodies[0].restitution");
  EXPECT_EQ(field_of(R"({"bodies": [{"name": "a"}, {"name": "a"}]})"), "bodies[1].name");
  EXPECT_EQ(field_of(R"({"bodies": [{"mas": 1}]})"), "bodies[0].mas");
  EXPECT_EQ(field_of(R"({"integrator": "leapfrog", "bodies": []})"), "integrator");
  EXPECT_EQ(field_of(R"({"toi": "guess", "bodies": []})"), "toi");
  EXPECT_EQ(field_of(R"({"dt": 0, "bodies": []})"), "dt");
  EXPECT_EQ(field_of(R"({"dt": 1e308, "bodies": []})"), "dt");
  EXPECT_EQ(field_of(R"({"max_overlap": -0.01, "bodies": []})"), "max_overlap");
  EXPECT_EQ(field_of(R"({"max_overlap": "1 cm", "bodies": []})"), "max_overlap");
  EXPECT_EQ(field_of(R"({"max_overlap": 1e-4, "bodies": []})"), "max_overlap");  // < 1 mm
  EXPECT_EQ(field_of(R"({"max_overlap": 0.01, "bodies": []})"), "<accepted>");
  EXPECT_EQ(field_of(R"({"max_overlap": 0, "bodies": []})"), "<accepted>");
  EXPECT_EQ(field_of(R"({"floor": {"restitution": -0.1}, "bodies": []})"), "floor.restitution");
  EXPECT_EQ(field_of(R"({"floor": {"friction": "x"}, "bodies": []})"), "floor.friction");
  EXPECT_EQ(field_of(R"({"gravity": [0, -9.81], "bodies": []})"), "gravity");
  EXPECT_EQ(field_of(R"({"bodies": 3})"), "bodies");
  EXPECT_EQ(field_of(R"({"description": 7, "bodies": []})"), "description");
  EXPECT_EQ(field_of(R"({"description": ")" + std::string(4097, 'x') + R"(", "bodies": []})"),
            "description");
  EXPECT_EQ(field_of(R"([1, 2])"), "");
  EXPECT_EQ(field_of(R"({"floor": null, "bodies": []})"), "<accepted>");
  json many = {{"bodies", json::array()}};
  for (std::size_t i = 0; i <= kMaxBodies; ++i) many["bodies"].push_back(json::object());
  EXPECT_THROW(scene_from_json(many), SceneParseError);
}

TEST(SceneIo, UnknownNameIsRefused) {
  EXPECT_THROW(load_scene("no-such-scene"), SceneParseError);
}

}  // namespace
}  // namespace tumble
