// The WebSocket stream (/ws) against a real server: scene messages, frame cadence and content.
#include <gtest/gtest.h>

#include <iostream>
#include <string>

#include "frame.hpp"
#include "server_fixture.hpp"
#include "tumble/world.hpp"

namespace tumble::server::test {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

class WsSessionTest : public ServerTest {
 protected:
  // Reads until a binary frame arrives (skipping text), failing the test on a timeout.
  DecodedFrame next_frame(WsClient& c) {
    for (int i = 0; i < 10; ++i) {
      const auto m = c.read(1s);
      if (!m) {
        ADD_FAILURE() << "no frame: " << c.last_error().message();
        return {};
      }
      if (m->text) continue;
      auto f = decode_frame(m->data);
      if (!f) ADD_FAILURE() << "undecodable frame";
      return f ? *f : DecodedFrame{};
    }
    ADD_FAILURE() << "only text messages";
    return {};
  }

  // The frames after the current one: reads and drops frames for `settle`, then returns one.
  DecodedFrame fresh_frame(WsClient& c, std::chrono::milliseconds settle = 60ms) {
    const auto until = std::chrono::steady_clock::now() + settle;
    DecodedFrame f = next_frame(c);
    while (std::chrono::steady_clock::now() < until) f = next_frame(c);
    return f;
  }
};

TEST_F(WsSessionTest, SceneMessageFirst) {
  WsClient c(port_);
  const auto m = c.read();
  ASSERT_TRUE(m);
  ASSERT_TRUE(m->text);
  const json j = json::parse(m->data);
  EXPECT_EQ(j["type"], "scene");
  EXPECT_EQ(j["scene"]["name"], "seed");
  EXPECT_EQ(j["faces"], json::parse("[[0,4,6,2],[1,3,7,5],[0,1,5,4],[2,6,7,3],[0,2,3,1],[4,5,7,6]]"));
  ASSERT_EQ(j["bodies"].size(), 1u);
  EXPECT_EQ(j["bodies"][0]["name"], "box");
  EXPECT_EQ(j["bodies"][0]["size"], json::parse("[1.0,1.0,1.0]"));
  EXPECT_EQ(j["bodies"][0]["color"], "#d9822b");
  const DecodedFrame f = next_frame(c);
  EXPECT_EQ(f.vertices.size(), 1u);
}

TEST_F(WsSessionTest, FiftyFramesPerSecond) {
  WsClient c(port_);
  next_frame(c);
  const auto start = std::chrono::steady_clock::now();
  int frames = 0;
  std::uint32_t last_number = 0;
  bool numbers_increase = true;
  while (std::chrono::steady_clock::now() - start < 2s) {
    const auto m = c.read(1s);
    ASSERT_TRUE(m) << c.last_error().message();
    if (m->text) continue;
    const auto f = decode_frame(m->data);
    ASSERT_TRUE(f);
    if (frames > 0 && f->frame_number <= last_number) numbers_increase = false;
    last_number = f->frame_number;
    ++frames;
  }
  EXPECT_NEAR(frames, 100, 10) << "frames in 2 s";
  EXPECT_TRUE(numbers_increase);
  EXPECT_EQ(server_->metrics().frames_dropped(), 0u);
}

TEST_F(WsSessionTest, FramesNeverRepeatAStaleState) {
  // The seed steps every 1/30 s, frames come every 20 ms: frames are interpolated.
  WsClient c(port_);
  next_frame(c);
  double last = -1;
  for (int i = 0; i < 40; ++i) {
    const DecodedFrame f = next_frame(c);
    EXPECT_GT(f.time, last) << "frame " << f.frame_number;
    last = f.time;
    EXPECT_EQ(f.flags & kFramePaused, 0);
  }
}

TEST_F(WsSessionTest, FrameMatchesTheEngineVertices) {
  WsClient c(port_);
  next_frame(c);
  ASSERT_EQ(http_post(port_, "/api/pause").status, 200u);
  const DecodedFrame f = fresh_frame(c);
  EXPECT_TRUE(f.flags & kFramePaused);
  const std::uint64_t steps = state()["step"];
  // The engine is deterministic: the same scene and steps give the same state.
  World world(load_scene("seed"));
  for (std::uint64_t i = 0; i < steps; ++i) world.step();
  EXPECT_DOUBLE_EQ(f.time, world.time());
  EXPECT_DOUBLE_EQ(f.energy, world.total_energy());
  ASSERT_EQ(f.vertices.size(), 1u);
  for (int v = 0; v < 8; ++v) {
    const Vec3 expected = world_vertex(world.body(0).s, world.body(0).c, v);
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(f.vertices[0][v][k], static_cast<float>(expected[k])) << "vertex " << v;
  }
}

TEST_F(WsSessionTest, ImpulseChangesTheNextFrames) {
  WsClient c(port_);
  http_post(port_, "/api/pause");
  const DecodedFrame before = fresh_frame(c);
  const std::uint64_t steps = state()["step"];
  const json impulse = {{"body", "box"}, {"impulse", {3, 0, 0}}, {"point", {0.2, 3.0, 0.1}}};
  ASSERT_EQ(http_post(port_, "/api/impulse", impulse.dump()).status, 200u);
  ASSERT_EQ(http_post(port_, "/api/step", R"({"steps": 2})").status, 200u);
  const DecodedFrame after = fresh_frame(c);
  World plain(load_scene("seed"));
  World pushed(load_scene("seed"));
  for (std::uint64_t i = 0; i < steps; ++i) {
    plain.step();
    pushed.step();
  }
  pushed.apply_impulse(0, {3, 0, 0}, {0.2, 3.0, 0.1});
  plain.step();
  plain.step();
  pushed.step();
  pushed.step();
  EXPECT_EQ(after.time, pushed.time());
  for (int v = 0; v < 8; ++v) {
    const Vec3 expected = world_vertex(pushed.body(0).s, pushed.body(0).c, v);
    const Vec3 unpushed = world_vertex(plain.body(0).s, plain.body(0).c, v);
    EXPECT_GT((expected - unpushed).norm(), 1e-3);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(after.vertices[0][v][k], static_cast<float>(expected[k]));
  }
  EXPECT_NE(after.vertices, before.vertices);
}

TEST_F(WsSessionTest, PauseFreezesSimTime) {
  WsClient c(port_);
  next_frame(c);
  http_post(port_, "/api/pause");
  const DecodedFrame first = fresh_frame(c);
  for (int i = 0; i < 10; ++i) {
    const DecodedFrame f = next_frame(c);
    EXPECT_EQ(f.time, first.time);
    EXPECT_EQ(f.vertices, first.vertices);
    EXPECT_TRUE(f.flags & kFramePaused);
  }
  http_post(port_, "/api/resume");
  const DecodedFrame later = fresh_frame(c, 100ms);
  EXPECT_GT(later.time, first.time);
  EXPECT_FALSE(later.flags & kFramePaused);
}

TEST_F(WsSessionTest, SceneMessageAfterResetBeforeItsFrames) {
  WsClient c(port_);
  next_frame(c);
  const std::size_t bodies = load_scene("many").bodies.size();
  ASSERT_NE(bodies, 1u);
  ASSERT_EQ(http_post(port_, "/api/reset", R"({"scene": "many"})").status, 200u);
  bool scene_seen = false;
  for (int i = 0; i < 30; ++i) {
    const auto m = c.read(1s);
    ASSERT_TRUE(m);
    if (m->text) {
      const json j = json::parse(m->data);
      EXPECT_EQ(j["scene"]["name"], "many");
      EXPECT_EQ(j["bodies"].size(), bodies);
      scene_seen = true;
      continue;
    }
    const auto f = decode_frame(m->data);
    ASSERT_TRUE(f);
    EXPECT_EQ(f->vertices.size(), scene_seen ? bodies : 1u) << "frame before its scene message";
  }
  EXPECT_TRUE(scene_seen);
}

TEST_F(WsSessionTest, BadRequestLeavesTheStreamRunning) {
  WsClient c(port_);
  const double t0 = next_frame(c).time;
  EXPECT_EQ(http_post(port_, "/api/reset", R"({"scene": {"bodies": [{"mass": 0}]}})").status,
            400u);
  EXPECT_EQ(http_post(port_, "/api/impulse", R"({"body": 9, "impulse": [0,1,0]})").status, 404u);
  const DecodedFrame f = fresh_frame(c, 100ms);
  EXPECT_GT(f.time, t0 + 0.05);
  EXPECT_EQ(f.vertices.size(), 1u);
}

TEST_F(WsSessionTest, ClientMessagesAreIgnoredButSizeLimited) {
  WsClient c(port_);
  next_frame(c);
  c.send_text("hello");
  next_frame(c);
  next_frame(c);
  c.send_text(std::string(5000, 'x'));
  bool closed = false;
  for (int i = 0; i < 20 && !closed; ++i) closed = !c.read(1s);
  EXPECT_TRUE(closed);
  EXPECT_EQ(c.last_error(), boost::beast::websocket::error::closed);
}

TEST_F(WsSessionTest, StopSendsACloseFrame) {
  WsClient c(port_);
  next_frame(c);
  std::thread stopper([this] { server_->stop(); });
  const auto t0 = std::chrono::steady_clock::now();
  bool closed = false;
  for (int i = 0; i < 100 && !closed; ++i) closed = !c.read(1s);
  stopper.join();
  EXPECT_TRUE(closed);
  EXPECT_EQ(c.last_error(), boost::beast::websocket::error::closed);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
}

TEST_F(WsSessionTest, NoViewerNoFrames) {
  std::uint32_t last = 0;
  {
    WsClient c(port_);
    last = next_frame(c).frame_number;
  }
  std::this_thread::sleep_for(300ms);  // 15 frame periods without a viewer.
  WsClient c(port_);
  const DecodedFrame f = next_frame(c);
  EXPECT_LE(f.frame_number, last + 3) << "frames were encoded while nobody watched";
}

// A viewer that completes the handshake and then never reads. The server keeps at most one
// frame pending for it (the newest; each one it replaces counts as dropped), so it costs one
// frame buffer, not a queue, and a reading viewer beside it still gets its frames.
class WsSessionStalled : public WsSessionTest {
  // 1000 boxes in free flight (no gravity, no floor): ~97 KB frames, so the kernel's buffers
  // of the stalled connection (a few MB on loopback) are full within the first second.
  Scene initial_scene() override {
    Scene s;
    s.world.name = "stalled";
    s.world.gravity = Vec3::Zero();
    s.world.floor.reset();
    for (int i = 0; i < 1000; ++i) {
      BodyDef b;
      b.name = "b" + std::to_string(i);
      b.position = Vec3(3.0 * (i % 10), 3.0 * (i / 10 % 10), 3.0 * (i / 100));
      b.angular_velocity = Vec3(0.3, 0.2, 0.1);
      s.bodies.push_back(b);
    }
    return s;
  }
};

TEST_F(WsSessionStalled, ANonReadingViewerIsKeptAtOnePendingFrame) {
  WsClient reader(port_);
  boost::asio::io_context ioc;
  boost::asio::ip::tcp::socket stalled = stalled_viewer(ioc, port_);
  // 4 s = 200 frames ≈ 19 MB for the stalled viewer: far more than its socket can hold.
  const std::uint64_t dropped_before = server_->metrics().frames_dropped();
  std::uint32_t first = 0, last = 0;
  int received = 0;
  for (const auto until = std::chrono::steady_clock::now() + 4s;
       std::chrono::steady_clock::now() < until;) {
    const DecodedFrame f = next_frame(reader);
    if (received++ == 0) first = f.frame_number;
    last = f.frame_number;
  }
  const std::uint64_t dropped = server_->metrics().frames_dropped() - dropped_before;
  std::cout << "[ measured ] 4 s with a stalled viewer: " << dropped << " frames replaced, reader got "
            << received << " of " << (last - first + 1) << " frames\n";
  EXPECT_EQ(server_->viewers(), 2u);
  EXPECT_GT(dropped, 50u) << "the stalled viewer's frames were queued, not replaced";
  EXPECT_LT(dropped, 200u);
  EXPECT_GE(received, 0.9 * (last - first + 1)) << "the reading viewer lost frames";
  EXPECT_GE(last - first + 1, 150u) << "the broadcast slowed down";
  stalled.close();
}

class WsSessionLimited : public WsSessionTest {
  void configure(ServerOptions& o) override { o.max_viewers = 1; }
};

TEST_F(WsSessionLimited, TooManyViewersIsRefused) {
  WsClient first(port_);
  next_frame(first);
  EXPECT_EQ(server_->viewers(), 1u);
  EXPECT_THROW(WsClient second(port_), boost::system::system_error);
  next_frame(first);
}

}  // namespace
}  // namespace tumble::server::test
