// The WebSocket stream (/ws) against a real server: scene messages, frame cadence and content.
#include <gtest/gtest.h>

#include <iostream>
#include <map>
#include <string>

#include "frame.hpp"
#include "ws_session.hpp"
#include "server_fixture.hpp"
#include "tumble/world.hpp"

namespace tumble::server::test {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

// A frame as a viewer sees it: the frame and every body's vertices after applying it.
struct Seen {
  DecodedFrame frame;
  std::vector<std::array<Vec3, 8>> vertices;  ///< Per body, m.
};

class WsSessionTest : public ServerTest {
 protected:
  // Reads until a binary frame arrives (skipping text), applies it to what this client holds
  // (failing the test when it does not apply), and returns it with the vertices held.
  Seen next_frame(WsClient& c) {
    for (int i = 0; i < 20; ++i) {
      const auto m = c.read(1s);
      if (!m) {
        ADD_FAILURE() << "no frame: " << c.last_error().message();
        return {};
      }
      if (m->text) {
        const json j = json::parse(m->data);
        if (j["type"] == "scene") decoders_[&c] = FrameDecoder{};
        continue;
      }
      auto f = decode_frame(m->data);
      if (!f) {
        ADD_FAILURE() << "undecodable frame";
        return {};
      }
      FrameDecoder& d = decoders_[&c];
      if (!d.apply(*f)) ADD_FAILURE() << "frame " << f->frame_number << " does not apply";
      Seen seen{*f, {}};
      for (std::size_t b = 0; b < d.bodies().size(); ++b) seen.vertices.push_back(d.vertices(b));
      return seen;
    }
    ADD_FAILURE() << "only text messages";
    return {};
  }
  // The frames after the current one: reads and applies frames for `settle`, returns one.
  Seen fresh_frame(WsClient& c, std::chrono::milliseconds settle = 60ms) {
    const auto until = std::chrono::steady_clock::now() + settle;
    Seen f = next_frame(c);
    while (std::chrono::steady_clock::now() < until) f = next_frame(c);
    return f;
  }
  // The next status message (skipping frames, which are applied).
  json next_status(WsClient& c) {
    for (int i = 0; i < 200; ++i) {
      const auto m = c.read(2s);
      if (!m) break;
      if (!m->text) {
        if (const auto f = decode_frame(m->data)) decoders_[&c].apply(*f);
        continue;
      }
      const json j = json::parse(m->data);
      if (j["type"] == "status") return j;
      if (j["type"] == "scene") decoders_[&c] = FrameDecoder{};
    }
    ADD_FAILURE() << "no status message";
    return json::object();
  }

  std::map<const WsClient*, FrameDecoder> decoders_;
};

// Largest distance between seen vertices and the engine's, m.
double vertex_error(const Seen& seen, const World& world) {
  double worst = 0;
  for (BodyId b = 0; b < world.bodies().size(); ++b)
    for (int v = 0; v < 8; ++v)
      worst = std::max(worst, (seen.vertices.at(b)[v] -
                               world_vertex(world.body(b).s, world.body(b).c, v)).norm());
  return worst;
}

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
  const Seen f = next_frame(c);
  EXPECT_EQ(f.vertices.size(), 1u);
  EXPECT_TRUE(f.frame.keyframe()) << "the first frame of a viewer is a keyframe";
}

// Every 20 ms tick of the frame clock is accounted for: a frame this viewer read, a frame
// replaced by a newer one while the previous write was still going, or a tick the timer
// skipped because it woke over a period late. A loaded machine (as CI's can be) moves ticks
// from the first kind to the others; the clock itself must keep 50 ticks a second.
TEST_F(WsSessionTest, FiftyFramesPerSecond) {
  WsClient c(port_);
  next_frame(c);
  const Metrics& metrics = server_->metrics();
  const std::uint64_t dropped0 = metrics.frames_dropped();
  const std::uint64_t skipped0 = metrics.ticks_skipped();
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
  const auto dropped = static_cast<int>(metrics.frames_dropped() - dropped0);
  const auto skipped = static_cast<int>(metrics.ticks_skipped() - skipped0);
  EXPECT_NEAR(frames + dropped + skipped, 100, 10)
      << "ticks in 2 s: " << frames << " frames read, " << dropped << " replaced, " << skipped
      << " skipped late";
  EXPECT_GT(frames, 50) << "most ticks reach a reading viewer";
  EXPECT_TRUE(numbers_increase);
}

TEST_F(WsSessionTest, FramesNeverRepeatAStaleState) {
  // The seed steps every 1/30 s, frames come every 20 ms: frames are interpolated.
  WsClient c(port_);
  next_frame(c);
  double last = -1;
  for (int i = 0; i < 40; ++i) {
    const DecodedFrame f = next_frame(c).frame;
    EXPECT_GT(f.time, last) << "frame " << f.frame_number;
    last = f.time;
    EXPECT_EQ(f.flags & kFramePaused, 0);
  }
}

TEST_F(WsSessionTest, FrameMatchesTheEngineVertices) {
  WsClient c(port_);
  next_frame(c);
  ASSERT_EQ(http_post(port_, "/api/pause").status, 200u);
  const Seen f = fresh_frame(c);
  EXPECT_TRUE(f.frame.flags & kFramePaused);
  const std::uint64_t steps = state()["step"];
  // The engine is deterministic: the same scene and steps give the same state.
  World world(load_scene("seed"));
  for (std::uint64_t i = 0; i < steps; ++i) world.step();
  EXPECT_DOUBLE_EQ(f.frame.time, world.time());
  EXPECT_DOUBLE_EQ(f.frame.energy, world.total_energy());
  ASSERT_EQ(f.vertices.size(), 1u);
  EXPECT_LE(vertex_error(f, world), 1e-4);
}

TEST_F(WsSessionTest, ImpulseChangesTheNextFrames) {
  WsClient c(port_);
  http_post(port_, "/api/pause");
  const Seen before = fresh_frame(c);
  const std::uint64_t steps = state()["step"];
  const json impulse = {{"body", "box"}, {"impulse", {3, 0, 0}}, {"point", {0.2, 3.0, 0.1}}};
  ASSERT_EQ(http_post(port_, "/api/impulse", impulse.dump()).status, 200u);
  ASSERT_EQ(http_post(port_, "/api/step", R"({"steps": 2})").status, 200u);
  const Seen after = fresh_frame(c);
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
  EXPECT_EQ(after.frame.time, pushed.time());
  for (int v = 0; v < 8; ++v) {
    const Vec3 expected = world_vertex(pushed.body(0).s, pushed.body(0).c, v);
    const Vec3 unpushed = world_vertex(plain.body(0).s, plain.body(0).c, v);
    EXPECT_GT((expected - unpushed).norm(), 1e-3);
  }
  EXPECT_LE(vertex_error(after, pushed), 1e-4);
  EXPECT_NE(after.vertices, before.vertices);
}

TEST_F(WsSessionTest, PauseFreezesSimTime) {
  WsClient c(port_);
  next_frame(c);
  http_post(port_, "/api/pause");
  const Seen first = fresh_frame(c);
  for (int i = 0; i < 5; ++i) {  // While paused, a frame every 200 ms carries no body.
    const Seen f = next_frame(c);
    EXPECT_EQ(f.frame.time, first.frame.time);
    EXPECT_EQ(f.vertices, first.vertices);
    EXPECT_TRUE(f.frame.bodies.empty());
    EXPECT_TRUE(f.frame.flags & kFramePaused);
  }
  http_post(port_, "/api/resume");
  const Seen later = fresh_frame(c, 100ms);
  EXPECT_GT(later.frame.time, first.frame.time);
  EXPECT_FALSE(later.frame.flags & kFramePaused);
}

TEST_F(WsSessionTest, SceneMessageAfterResetBeforeItsFrames) {
  WsClient c(port_);
  next_frame(c);
  const std::size_t bodies = load_scene("many").bodies.size();
  ASSERT_NE(bodies, 1u);
  ASSERT_EQ(http_post(port_, "/api/reset", R"({"scene": "many"})").status, 200u);
  bool scene_seen = false, keyframe_seen = false;
  for (int i = 0; i < 30; ++i) {
    const auto m = c.read(1s);
    ASSERT_TRUE(m);
    if (m->text) {
      const json j = json::parse(m->data);
      if (j["type"] != "scene") continue;
      EXPECT_EQ(j["scene"]["name"], "many");
      EXPECT_EQ(j["bodies"].size(), bodies);
      scene_seen = true;
      continue;
    }
    const auto f = decode_frame(m->data);
    ASSERT_TRUE(f);
    EXPECT_EQ(f->body_count, scene_seen ? bodies : 1u) << "frame before its scene message";
    if (scene_seen && !keyframe_seen) EXPECT_TRUE(f->keyframe()) << "after a reset: a keyframe";
    keyframe_seen = keyframe_seen || (scene_seen && f->keyframe());
  }
  EXPECT_TRUE(scene_seen);
  EXPECT_TRUE(keyframe_seen);
}

TEST_F(WsSessionTest, BadRequestLeavesTheStreamRunning) {
  WsClient c(port_);
  const double t0 = next_frame(c).frame.time;
  EXPECT_EQ(http_post(port_, "/api/reset", R"({"scene": {"bodies": [{"mass": 0}]}})").status,
            400u);
  EXPECT_EQ(http_post(port_, "/api/impulse", R"({"body": 9, "impulse": [0,1,0]})").status, 404u);
  const Seen f = fresh_frame(c, 100ms);
  EXPECT_GT(f.frame.time, t0 + 0.05);
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
    last = next_frame(c).frame.frame_number;
  }
  std::this_thread::sleep_for(300ms);  // 15 frame periods without a viewer.
  WsClient c(port_);
  const DecodedFrame f = next_frame(c).frame;
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
    const DecodedFrame f = next_frame(reader).frame;
    if (received++ == 0) first = f.frame_number;
    last = f.frame_number;
  }
  const std::uint64_t dropped = server_->metrics().frames_dropped() - dropped_before;
  std::cout << "[ measured ] 4 s with a stalled viewer: " << dropped << " frames replaced, reader got "
            << received << " of " << (last - first + 1) << " frames\n";
  EXPECT_EQ(server_->viewers(), 2u);
  EXPECT_GT(dropped, 50u) << "the stalled viewer's frames were queued, not replaced";
  EXPECT_LE(dropped, last - first + 1) << "only the stalled viewer drops, at most each frame";
  // Each session holds at most the one frame it is writing: the stalled one its stuck frame.
  EXPECT_LE(server_->metrics().frames_in_flight(), 2);
  EXPECT_GE(server_->metrics().frames_in_flight(), 1);
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

// ---- Protocol version 2: deltas, status, pace (issue 13) ---------------------------------

// Two boxes without gravity: a spins, b stays still until kicked.
class WsStreamTest : public WsSessionTest {
  Scene initial_scene() override {
    return scene_from_json(json::parse(R"({"name": "two", "gravity": [0, 0, 0], "floor": null,
      "bodies": [{"name": "a", "position": [0, 0, 0], "angular_velocity": [0, 1, 0]},
                 {"name": "b", "position": [3, 0, 0]}]})"));
  }
};

TEST_F(WsStreamTest, DeltasCarryOnlyTheBodiesThatMoveAndAKickedOneJoins) {
  WsClient c(port_);
  EXPECT_TRUE(next_frame(c).frame.keyframe());
  for (int i = 0; i < 20; ++i) {
    const Seen f = next_frame(c);
    EXPECT_FALSE(f.frame.keyframe());
    ASSERT_EQ(f.frame.bodies.size(), 1u) << "only the spinning box";
    EXPECT_EQ(f.frame.bodies[0].index, 0u);
  }
  ASSERT_EQ(http_post(port_, "/api/impulse", R"({"body": "b", "impulse": [0, 1, 0]})").status, 200u);
  bool kicked_seen = false;
  for (int i = 0; i < 20 && !kicked_seen; ++i) {
    const Seen f = next_frame(c);
    for (const DecodedBody& d : f.frame.bodies) kicked_seen = kicked_seen || d.index == 1;
  }
  EXPECT_TRUE(kicked_seen) << "the kicked box is in the deltas";
  const Seen f = next_frame(c);
  EXPECT_EQ(f.frame.bodies.size(), 2u) << "both move now";
  EXPECT_GT(f.vertices[1][0].y(), -0.5) << "b has risen";
}

TEST_F(WsStreamTest, StatusMessageCarriesTheServerState) {
  WsClient c(port_);
  const json status = next_status(c);
  EXPECT_EQ(status["paused"], false);
  EXPECT_TRUE(status["integrator"].is_string() && !status["integrator"].get<std::string>().empty());
  EXPECT_EQ(status["bodies"], 2);
  EXPECT_EQ(status["awake"].get<int>() + status["asleep"].get<int>() + status["frozen"].get<int>(), 2);
  EXPECT_TRUE(status["real_time_factor"].is_number());
  EXPECT_TRUE(status["step"].is_number_unsigned());
  EXPECT_TRUE(status["time"].is_number());
  EXPECT_EQ(status["dropped"], 0);
  ASSERT_EQ(http_post(port_, "/api/integrator", R"({"integrator": "rk4"})").status, 200u);
  ASSERT_EQ(http_post(port_, "/api/pause").status, 200u);
  const auto asked = std::chrono::steady_clock::now();
  json later = next_status(c);
  while (later["paused"] != true && std::chrono::steady_clock::now() - asked < 3s)
    later = next_status(c);
  EXPECT_EQ(later["paused"], true);
  EXPECT_EQ(later["integrator"], "rk4");
  EXPECT_EQ(later["real_time_factor"], 0.0);
  EXPECT_LT(std::chrono::steady_clock::now() - asked, 500ms) << "a change is told at once";
}

TEST_F(WsStreamTest, ViewersInStepShareOneEncoding) {
  std::vector<std::unique_ptr<WsClient>> viewers;
  for (int i = 0; i < 5; ++i) viewers.push_back(std::make_unique<WsClient>(port_));
  for (auto& v : viewers) next_frame(*v);
  const std::uint64_t encodings0 = server_->broadcaster().store().encodings();
  std::uint32_t first = 0, last = 0;
  for (int i = 0; i < 25; ++i)
    for (std::size_t k = 0; k < viewers.size(); ++k) {
      const std::uint32_t n = next_frame(*viewers[k]).frame.frame_number;
      if (i == 0 && k == 0) first = n;
      last = std::max(last, n);
    }
  const std::uint64_t encodings = server_->broadcaster().store().encodings() - encodings0;
  const std::uint64_t frames = last - first + 1;
  std::cout << "[ measured ] 5 viewers, " << frames << " frames: " << encodings << " encodings\n";
  EXPECT_LE(encodings, frames + frames / 2 + 5) << "encoded per viewer, not once per frame";
}

TEST_F(WsStreamTest, AClientThatStopsAcknowledgingGetsAtMostTheWindow) {
  WsClient c(port_);
  const Seen f = next_frame(c);
  c.send_text(json{{"type", "ack"}, {"frame", f.frame.frame_number}}.dump());
  int frames = 0;
  for (const auto until = std::chrono::steady_clock::now() + 1s;
       std::chrono::steady_clock::now() < until;) {
    const auto m = c.read(1s);
    if (!m) break;
    frames += m->text ? 0 : 1;
  }
  EXPECT_LE(frames, static_cast<int>(WsSession::kAckWindow)) << "50 frames were due in 1 s";
  EXPECT_GE(frames, static_cast<int>(WsSession::kAckWindow) - 1);
}

// The vertices a viewer rebuilds against GET /api/state's poses (paused: the same instant).
class WsStreamMany : public WsSessionTest {
  Scene initial_scene() override { return load_scene("many"); }
};

TEST_F(WsStreamMany, VerticesMatchApiStateWithinATenthOfAMillimetre) {
  WsClient c(port_);
  next_frame(c);
  std::this_thread::sleep_for(500ms);
  ASSERT_EQ(http_post(port_, "/api/pause").status, 200u);
  const Seen f = fresh_frame(c, 400ms);
  const json s = state();
  ASSERT_EQ(s["time"].get<double>(), f.frame.time);
  const Scene scene = load_scene("many");
  double worst = 0;
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    const json& p = s["bodies"][b];
    BodyState pose;
    pose.x = Vec3(p["position"][0], p["position"][1], p["position"][2]);
    pose.R = Quat(p["orientation"][0], p["orientation"][1], p["orientation"][2],
                  p["orientation"][3]).normalized().toRotationMatrix();
    BodyConstants constants;
    constants.half_extents = 0.5 * scene.bodies[b].size;
    for (int v = 0; v < 8; ++v)
      worst = std::max(worst, (f.vertices[b][v] - world_vertex(pose, constants, v)).norm());
  }
  std::cout << "[ measured ] worst vertex error against /api/state: " << worst * 1e6 << " µm\n";
  EXPECT_LE(worst, 1e-4);
}

// Boxes resting on the floor fall asleep; then only a small status and a heartbeat flow.
class WsStreamResting : public WsSessionTest {
  Scene initial_scene() override { return load_scene("resting"); }
};

TEST_F(WsStreamResting, ASleepingSceneSendsAlmostNothing) {
  WsClient c(port_);
  json status = next_status(c);
  for (int i = 0; i < 30 && status["asleep"] != status["bodies"]; ++i) status = next_status(c);
  ASSERT_EQ(status["asleep"], status["bodies"]) << "the resting scene never slept";
  fresh_frame(c, 300ms);  // The frame that tells the last body's sleep.
  std::size_t bytes = 0, bodies_sent = 0;
  for (const auto until = std::chrono::steady_clock::now() + 2s;
       std::chrono::steady_clock::now() < until;) {
    const auto m = c.read(1s);
    ASSERT_TRUE(m);
    bytes += m->data.size();
    if (!m->text) bodies_sent += decode_frame(m->data)->bodies.size();
  }
  std::cout << "[ measured ] asleep: " << bytes / 2 << " bytes/s\n";
  EXPECT_EQ(bodies_sent, 0u) << "a sleeping body costs nothing after its last change";
  EXPECT_LE(bytes, 2u * 2000u);
}

}  // namespace
}  // namespace tumble::server::test
