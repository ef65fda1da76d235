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

/// A body state at centre x (m) turned by R, at rest.
inline BodyState pose(const Vec3& x, const Mat3& R) {
  BodyState s;
  s.x = x;
  s.R = R;
  return s;
}

/// A bundled scene with one setting changed.
inline Scene bundled(const std::string& name) { return load_scene(name); }

/// Four spinning boxes fall at `speed` onto one that rests on the floor (dt = 1/60).
inline Scene falling_boxes(double speed, double spin, double max_overlap) {
  Scene s;
  s.world.max_overlap = max_overlap;
  s.world.floor = Floor{0.0, 0.0, 0.5};
  BodyDef base;
  base.name = "base";
  base.position = {0, 0.5, 0};
  s.bodies.push_back(base);
  for (int k = 0; k < 4; ++k) {
    BodyDef b;
    b.name = "falling" + std::to_string(k);
    b.position = k == 0 ? Vec3(0.3, 1.9, 0.1) : Vec3(0.2 * k - 0.4, 1.2 + 2.0 * k, -0.1 * k);
    b.orientation = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
    b.velocity = {0, -speed, 0};
    b.angular_velocity = {spin, 0.3 * spin, -0.5 * spin};
    s.bodies.push_back(b);
  }
  return s;
}

}  // namespace tumble::testing
