#include "frame.hpp"

#include <gtest/gtest.h>

#include <iostream>
#include <limits>
#include <random>

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

// A keyframe of `s` at its own time, decoded and applied.
FrameDecoder keyframe_of(const Snapshot& s, std::uint32_t number = 0) {
  const auto state = make_frame_state(s, number, s.time, nullptr);
  FrameDecoder decoder;
  const auto f = decode_frame(encode_frame(*state, nullptr));
  EXPECT_TRUE(f && decoder.apply(*f));
  return decoder;
}

// Largest distance between a body's rebuilt vertices and the engine's, m.
double vertex_error(const FrameDecoder& d, const World& world) {
  double worst = 0;
  for (BodyId b = 0; b < world.bodies().size(); ++b) {
    const auto v = d.vertices(b);
    for (int i = 0; i < 8; ++i)
      worst = std::max(worst, (v[i] - world_vertex(world.body(b).s, world.body(b).c, i)).norm());
  }
  return worst;
}

TEST(Frame, KeyframeLayoutAndEngineVertices) {
  World world(two_boxes());
  for (int i = 0; i < 7; ++i) world.step();
  const Snapshot s = snapshot_of(world, nullptr);
  const auto state = make_frame_state(s, 42, s.time, nullptr);
  const std::string bytes = encode_frame(*state, nullptr);
  // Header, then per body: format byte, 3 × int32 centre, 9 axes: int32 for box a (3 m:
  // int16 would be coarser than 2⁻¹⁵ m), int16 for box b (0.5 m).
  ASSERT_EQ(bytes.size(), kFrameHeaderBytes + (1 + 12 + 36) + (1 + 12 + 18));
  EXPECT_TRUE(state->bodies[0].wide);
  EXPECT_FALSE(state->bodies[1].wide);
  EXPECT_EQ(state->bodies[1].exponent, 16);  // 0.25 m · 2¹⁷ would overflow int16
  EXPECT_EQ(bytes.substr(0, 4), "TMBL");
  const auto f = decode_frame(bytes);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->version, 2);
  EXPECT_EQ(f->flags, kFrameKeyframe);
  EXPECT_EQ(f->frame_number, 42u);
  EXPECT_EQ(f->base_number, 42u);
  EXPECT_EQ(f->body_count, 2u);
  EXPECT_DOUBLE_EQ(f->time, world.time());
  EXPECT_DOUBLE_EQ(f->energy, world.total_energy());
  FrameDecoder d;
  ASSERT_TRUE(d.apply(*f));
  EXPECT_LE(vertex_error(d, world), 1e-4);
  EXPECT_EQ(d.bodies()[0].activity, 0);
}

TEST(Frame, LittleEndianHeaderBytes) {
  World world(two_boxes());
  Snapshot s = snapshot_of(world, nullptr);
  s.paused = true;
  s.frozen = 1;
  const std::string bytes = encode_frame(*make_frame_state(s, 0x01020304, 0.0, nullptr), nullptr);
  EXPECT_EQ(static_cast<unsigned char>(bytes[4]), 2);  // version, low byte first
  EXPECT_EQ(static_cast<unsigned char>(bytes[5]), 0);
  EXPECT_EQ(static_cast<unsigned char>(bytes[6]), 7);  // flags: paused | some frozen | key
  EXPECT_EQ(static_cast<unsigned char>(bytes[8]), 4);
  EXPECT_EQ(static_cast<unsigned char>(bytes[11]), 1);
  EXPECT_EQ(static_cast<unsigned char>(bytes[12]), 4);  // base = itself for a keyframe
  EXPECT_EQ(static_cast<unsigned char>(bytes[16]), 2);  // N = 2
  EXPECT_EQ(static_cast<unsigned char>(bytes[20]), 2);  // M = 2
}

// The bound of docs/protocol.md: per coordinate ≤ 2⁻¹⁷ (centre) + 3 · 2⁻¹⁶ (axes at e ≥ 15),
// so ≤ √3 · 5.34e-5 = 9.3e-5 m; boxes up to 10 m, centres up to ±10 km, any orientation.
TEST(Frame, VertexErrorWithinATenthOfAMillimetre) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> size(0.01, 10.0), where(-1e4, 1e4), unit(-1, 1);
  Scene scene;
  scene.world.gravity = Vec3::Zero();
  scene.world.floor.reset();
  for (int i = 0; i < 200; ++i) {
    BodyDef b;
    b.name = "b" + std::to_string(i);
    b.size = Vec3{size(random), size(random), i % 4 == 0 ? 10.0 : size(random)};
    b.position = Vec3{where(random), where(random), where(random)};
    const double w = unit(random), x = unit(random), y = unit(random), z = unit(random);
    b.orientation = Quat(w, x, y, z).normalized();
    scene.bodies.push_back(b);
  }
  World world(scene);
  const FrameDecoder d = keyframe_of(snapshot_of(world, nullptr));
  const double error = vertex_error(d, world);
  std::cout << "[ measured ] worst vertex error of 200 boxes up to 10 m within ±10 km: "
            << error * 1e6 << " µm\n";
  EXPECT_LE(error, 1e-4);
  EXPECT_GT(error, 0.0) << "quantised, so not exact";
  bool some_wide = false;
  for (const QuantBody& q : d.bodies()) some_wide = some_wide || q.wide;
  EXPECT_TRUE(some_wide) << "10 m boxes need the wide encoding";
}

TEST(Frame, DeltaCarriesOnlyTheBodiesThatMoved) {
  World world(two_boxes());
  Snapshot s0 = snapshot_of(world, nullptr);
  const auto f0 = make_frame_state(s0, 0, s0.time, nullptr);
  // Only body b moves (a copy of the poses with b shifted 2 cm).
  Snapshot s1 = s0;
  auto poses = std::make_shared<std::vector<BodyPose>>(*s0.bodies);
  (*poses)[1].position.x() += 0.02;
  s1.bodies = poses;
  const auto f1 = make_frame_state(s1, 1, s1.time, f0.get());
  const auto delta = decode_frame(encode_frame(*f1, f0.get()));
  ASSERT_TRUE(delta);
  EXPECT_FALSE(delta->keyframe());
  EXPECT_EQ(delta->base_number, 0u);
  ASSERT_EQ(delta->bodies.size(), 1u);
  EXPECT_EQ(delta->bodies[0].index, 1u);
  EXPECT_FALSE(delta->bodies[0].absolute) << "a 2 cm move fits an int16 centre delta";
  EXPECT_EQ(delta->bodies[0].body.centre[0], std::lround(0.02 * 65536));
  FrameDecoder d = keyframe_of(s0);
  ASSERT_TRUE(d.apply(*delta));
  const auto v = d.vertices(1);
  const BodyState moved{(*poses)[1].position, (*poses)[1].rotation};
  for (int i = 0; i < 8; ++i)
    EXPECT_LE((v[i] - world_vertex(moved, s0.scene->constants[1], i)).norm(), 1e-4);
  // Nothing changed since f1: a delta with no body, the header only.
  const auto f2 = make_frame_state(s1, 2, s1.time, f1.get());
  EXPECT_EQ(encode_frame(*f2, f1.get()).size(), kFrameHeaderBytes);
  // Against the older base f0 the same frame still carries body b.
  EXPECT_EQ(decode_frame(encode_frame(*f2, f0.get()))->bodies.size(), 1u);
}

TEST(Frame, ADeltaAppliesOnlyToItsBase) {
  World world(two_boxes());
  const Snapshot s0 = snapshot_of(world, nullptr);
  const auto f0 = make_frame_state(s0, 5, s0.time, nullptr);
  world.step();
  const Snapshot s1 = snapshot_of(world, &s0);
  const auto f1 = make_frame_state(s1, 6, s1.time, f0.get());
  const auto delta = decode_frame(encode_frame(*f1, f0.get()));
  ASSERT_TRUE(delta);
  FrameDecoder empty;
  EXPECT_FALSE(empty.apply(*delta)) << "a delta before any keyframe";
  FrameDecoder other = keyframe_of(s0, 4);
  EXPECT_FALSE(other.apply(*delta)) << "a delta against frame 5 applied on frame 4";
}

TEST(Frame, ANonFiniteBodyKeepsItsLastFinitePose) {
  World world(two_boxes());
  const Snapshot s0 = snapshot_of(world, nullptr);
  const auto f0 = make_frame_state(s0, 0, s0.time, nullptr);
  Snapshot s1 = s0;
  auto poses = std::make_shared<std::vector<BodyPose>>(*s0.bodies);
  (*poses)[0].position.y() = std::numeric_limits<double>::quiet_NaN();
  (*poses)[0].activity = Activity::frozen;
  s1.bodies = poses;
  s1.frozen = 1;
  const auto f1 = make_frame_state(s1, 1, s1.time, f0.get());
  EXPECT_EQ(f1->bodies[0].centre, f0->bodies[0].centre);
  EXPECT_EQ(f1->bodies[0].activity, 2);
  FrameDecoder d = keyframe_of(s0);
  ASSERT_TRUE(d.apply(*decode_frame(encode_frame(*f1, f0.get()))));
  for (const Vec3& v : d.vertices(0)) EXPECT_TRUE(v.allFinite());
  EXPECT_LE(vertex_error(d, world), 1e-4) << "body a shown where it last was finite";
}

TEST(Frame, InterpolatesBetweenSteps) {
  World world(two_boxes());
  const Snapshot s0 = snapshot_of(world, nullptr);
  world.step();
  const Snapshot s1 = snapshot_of(world, &s0);
  const double mid = 0.5 * (s0.time + s1.time);
  const auto at = [](const Snapshot& s, double time) {
    FrameDecoder d;
    d.apply(*decode_frame(encode_frame(*make_frame_state(s, 0, time, nullptr), nullptr)));
    return d;
  };
  const FrameDecoder f = at(s1, mid), f0 = at(s0, s0.time), f1 = at(s1, s1.time);
  EXPECT_DOUBLE_EQ(f.last()->time, mid);
  // Box b flies at 1 m/s along x without rotating: its vertices are halfway.
  for (int v = 0; v < 8; ++v)
    EXPECT_LE((f.vertices(1)[v] - 0.5 * (f0.vertices(1)[v] + f1.vertices(1)[v])).norm(), 1e-4);
  // Box a rotates: interpolated, it stays rigid (every edge keeps its length).
  const auto edge = [&](int i, int j) { return (f.vertices(0)[i] - f.vertices(0)[j]).norm(); };
  EXPECT_NEAR(edge(0, 1), 1.0, 1e-4);
  EXPECT_NEAR(edge(0, 2), 2.0, 1e-4);
  EXPECT_NEAR(edge(0, 4), 3.0, 1e-4);
  // At the current step's time (or later) the current pose is shown exactly.
  EXPECT_EQ(at(s1, s1.time + 1).bodies(), f1.bodies());
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
  EXPECT_FALSE(decode_frame(std::string(40, '\0')));
  World world(two_boxes());
  const Snapshot s = snapshot_of(world, nullptr);
  const std::string good = encode_frame(*make_frame_state(s, 0, 0.0, nullptr), nullptr);
  ASSERT_TRUE(decode_frame(good));
  EXPECT_FALSE(decode_frame(std::string_view(good).substr(0, good.size() - 1)));
  EXPECT_FALSE(decode_frame(good + "x"));
  std::string bad = good;
  bad[4] = 1;  // version 1
  EXPECT_FALSE(decode_frame(bad));
  bad = good;
  bad[20] = 3;  // M > N
  EXPECT_FALSE(decode_frame(bad));
  bad = good;
  bad[6] = 0;  // not a keyframe: then an index list is due and the lengths disagree
  EXPECT_FALSE(decode_frame(bad));
}

}  // namespace
}  // namespace tumble::server
