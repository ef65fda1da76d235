#pragma once
// Shared helpers for engine tests: worlds from inline JSON scenes, bundled scenes.
#include <string>

#include <gtest/gtest.h>

#include "tumble/scene_io.hpp"
#include "tumble/world.hpp"

namespace tumble::testing {

/// A World built from an inline JSON scene (fails the test on a parse error).
inline World world_from_json(const std::string& text) {
  return World(scene_from_json(nlohmann::json::parse(text)));
}

/// A bundled scene with one setting changed.
inline Scene bundled(const std::string& name) { return load_scene(name); }

}  // namespace tumble::testing
