#pragma once
/// Scene JSON ⇄ engine definitions (the tumble_scene_io target; nlohmann-json).
/// Pure functions; thread-safe.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "tumble/scene.hpp"

namespace tumble {

/// A scene that could not be read: carries the offending field ("bodies[0].mass").
struct SceneParseError : std::runtime_error {
  SceneParseError(std::string field, const std::string& message)
      : std::runtime_error(message), field(std::move(field)) {}
  std::string field;  ///< Field name, "" for the whole document.
};

/// Parses and validates a scene object; throws SceneParseError naming the field.
/// Unknown keys are refused (a typo must not pass silently).
Scene scene_from_json(const nlohmann::json& j);

/// Writes a scene back as JSON (the same schema scene_from_json reads).
nlohmann::json scene_to_json(const Scene& scene);

/// Directory of the bundled scenes: $TUMBLE_SCENES_DIR if set, else the source tree's.
std::filesystem::path bundled_scenes_dir();

/// Names of the bundled scenes (file stems, sorted).
std::vector<std::string> bundled_scene_names();

/// Loads a scene from a path, or a bundled name ("seed"); throws SceneParseError.
Scene load_scene(const std::string& name_or_path);

}  // namespace tumble
