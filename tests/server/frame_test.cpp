#include "frame.hpp"

#include <gtest/gtest.h>

#include "tumble/scene_io.hpp"
#include "tumble/world.hpp"

namespace tumble::server {
namespace {

Scene two_boxes() {
  return scene_from_json(nlohmann::json::parse(R"({
    "name": "two", "dt": 0.01, "integrator": "rk4",
    "bodies": [
      {"name": "a", "size": [1, 2, 3], "mass": 2, "position": [0, 5, 0],
       "angular_velocity": [1, 2, 3]},
      {"name": "b", "size": [0.5, 0.5, 0.5], "position": [3, 2, 1],
       "orientation": [0.9238795325112867, 0.3826834323650898, 0, 0],
       "velocity": [1, 0, 0]}
    ]})"));
}

// A snapshot of `world` as the simulation thread would publish it.
Snapshot snapshot_of(const World& world, const Snapshot* previous) {
  Snapshot s;
  std::vector<BodyConstants> constants;
  auto poses = std::make_shared<std::vector<BodyPose>>();
  for (const Body& b : world.bodies()) {
    constants.push_back(b.c);
    poses->push_back({b.s.x, b.s.R, velocity(b.s, b.c), angular_velocity(b.s, b.c), b.activity});
  }
  s.scene = previous ? previous->scene : make_scene_info(1, world.scene(), constants);
  s.time = world.time();
  s.step = world.step_count();
  s.energy = world.total_energy();
  s.bodies = poses;
  if (previous) {
    s.previous_bodies = previous->bodies;
    s.previous_time = previous->time;
  }
  return s;
}

TEST(Frame, LayoutAndEngineVertices) {
  World world(two_boxes());
  for (int i = 0; i < 7; ++i) world.step();
  const Snapshot s = snapshot_of(world, nullptr);
  const std::string bytes = encode_frame(s, 42, s.time);
  ASSERT_EQ(bytes.size(), 32u + 97u * 2u);
  EXPECT_EQ(bytes.substr(0, 4), "TMBL");
  const auto f = decode_frame(bytes);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->version, 1);
  EXPECT_EQ(f->flags, 0);
  EXPECT_EQ(f->frame_number, 42u);
  EXPECT_DOUBLE_EQ(f->time, world.time());
  EXPECT_DOUBLE_EQ(f->energy, world.total_energy());
  ASSERT_EQ(f->vertices.size(), 2u);
  for (BodyId b = 0; b < 2; ++b)
    for (int v = 0; v < 8; ++v) {
      const Vec3 expected = world_vertex(world.body(b).s, world.body(b).c, v);
      for (int k = 0; k < 3; ++k) EXPECT_EQ(f->vertices[b][v][k], static_cast<float>(expected[k]));
    }
  EXPECT_EQ(f->activity, (std::vector<std::uint8_t>{0, 0}));
}

TEST(Frame, LittleEndianHeaderBytes) {
  World world(two_boxes());
  Snapshot s = snapshot_of(world, nullptr);
  s.paused = true;
  s.frozen = 1;
  const std::string bytes = encode_frame(s, 0x01020304, 0.0);
  EXPECT_EQ(static_cast<unsigned char>(bytes[4]), 1);  // version, low byte first
  EXPECT_EQ(static_cast<unsigned char>(bytes[5]), 0);
  EXPECT_EQ(static_cast<unsigned char>(bytes[6]), 3);  // flags: paused | some frozen
  EXPECT_EQ(static_cast<unsigned char>(bytes[8]), 4);
  EXPECT_EQ(static_cast<unsigned char>(bytes[11]), 1);
  EXPECT_EQ(static_cast<unsigned char>(bytes[12]), 2);  // N = 2
}

TEST(Frame, InterpolatesBetweenSteps) {
  World world(two_boxes());
  const Snapshot s0 = snapshot_of(world, nullptr);
  world.step();
  const Snapshot s1 = snapshot_of(world, &s0);
  const double mid = 0.5 * (s0.time + s1.time);
  const auto f = decode_frame(encode_frame(s1, 1, mid));
  ASSERT_TRUE(f);
  EXPECT_DOUBLE_EQ(f->time, mid);
  // Box b flies at 1 m/s along x without rotating: its vertices are halfway.
  const auto f0 = decode_frame(encode_frame(s0, 0, s0.time));
  const auto f1 = decode_frame(encode_frame(s1, 0, s1.time));
  for (int v = 0; v < 8; ++v)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(f->vertices[1][v][k], 0.5f * (f0->vertices[1][v][k] + f1->vertices[1][v][k]),
                  1e-5);
  // Box a rotates: interpolated, it stays rigid (every edge keeps its length).
  const auto edge = [&](const DecodedFrame& g, int i, int j) {
    Vec3 d;
    for (int k = 0; k < 3; ++k) d[k] = g.vertices[0][i][k] - g.vertices[0][j][k];
    return d.norm();
  };
  EXPECT_NEAR(edge(*f, 0, 1), 1.0, 1e-5);
  EXPECT_NEAR(edge(*f, 0, 2), 2.0, 1e-5);
  EXPECT_NEAR(edge(*f, 0, 4), 3.0, 1e-5);
  // At the current step's time (or later) the current pose is shown exactly.
  const auto late = decode_frame(encode_frame(s1, 2, s1.time));
  EXPECT_EQ(late->vertices, f1->vertices);
}

TEST(Frame, FrameTimeFollowsTheRealTimeClock) {
  World world(two_boxes());
  const Snapshot s0 = snapshot_of(world, nullptr);
  world.step();
  Snapshot s1 = snapshot_of(world, &s0);
  s1.wall_time = Clock::now();
  EXPECT_DOUBLE_EQ(frame_time(s1, s1.wall_time), s1.time);
  EXPECT_NEAR(frame_time(s1, s1.wall_time - std::chrono::milliseconds(4)), s1.time - 0.004, 1e-9);
  EXPECT_DOUBLE_EQ(frame_time(s1, s1.wall_time - std::chrono::seconds(1)), s0.time);
  EXPECT_DOUBLE_EQ(frame_time(s1, s1.wall_time + std::chrono::seconds(1)), s1.time);
  s1.paused = true;
  EXPECT_DOUBLE_EQ(frame_time(s1, s1.wall_time - std::chrono::milliseconds(4)), s1.time);
}

TEST(Frame, DecoderRefusesMalformedBytes) {
  EXPECT_FALSE(decode_frame(""));
  EXPECT_FALSE(decode_frame(std::string(32, '\0')));
  World world(two_boxes());
  std::string bytes = encode_frame(snapshot_of(world, nullptr), 0, 0.0);
  EXPECT_FALSE(decode_frame(std::string_view(bytes).substr(0, bytes.size() - 1)));
  bytes[4] = 2;
  EXPECT_FALSE(decode_frame(bytes));
}

}  // namespace
}  // namespace tumble::server
