// libFuzzer target: arbitrary bytes as a scene document. Parsing must either refuse with a
// SceneParseError or give a scene the World accepts and can step without going non-finite
// silently (a frozen body is reported, never a crash).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tumble/scene_io.hpp"
#include "tumble/world.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto json = nlohmann::json::parse(data, data + size, nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded()) return 0;
  tumble::Scene scene;
  try {
    scene = tumble::scene_from_json(json);
  } catch (const tumble::SceneParseError&) {
    return 0;
  }
  if (scene.bodies.size() > 64) return 0;  // keep each input fast
  scene.world.dt = std::min(scene.world.dt, 0.05);
  scene.world.toi_tolerance = std::min(scene.world.toi_tolerance, scene.world.dt);
  tumble::World world(scene);
  for (int i = 0; i < 8; ++i) world.step();
  for (const tumble::Body& b : world.bodies())
    if (!tumble::all_finite(b.s.x)) __builtin_trap();  // frozen bodies keep finite states
  return 0;
}
