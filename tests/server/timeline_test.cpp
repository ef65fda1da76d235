// The timeline (docs/protocol.md, "Timeline"): exact seek, resume from the past, playback,
// speed, the memory bound, recordings replayed by tumble-sim, and bad input. The Timeline
// class alone first (bit-for-bit against a straight run of the engine), then through a real
// server on 127.0.0.1.
#include <algorithm>
#include <gtest/gtest.h>
#include <malloc.h>

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <thread>

#include "../sanitized.hpp"
#include "child_process.hpp"
#include "server_fixture.hpp"
#include "world_api_test_base.hpp"
#include "timeline.hpp"

namespace tumble::server::test {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

// ---- Timeline alone -----------------------------------------------------------------------

/// True when every body's state (x, R, P, L) and activity are equal bit for bit.
bool same_bodies(const World& a, const World& b) {
  if (a.bodies().size() != b.bodies().size()) return false;
  for (std::size_t i = 0; i < a.bodies().size(); ++i) {
    const BodyState& x = a.bodies()[i].s;
    const BodyState& y = b.bodies()[i].s;
    if (std::memcmp(x.x.data(), y.x.data(), sizeof(double) * 3) != 0 ||
        std::memcmp(x.R.data(), y.R.data(), sizeof(double) * 9) != 0 ||
        std::memcmp(x.P.data(), y.P.data(), sizeof(double) * 3) != 0 ||
        std::memcmp(x.L.data(), y.L.data(), sizeof(double) * 3) != 0 ||
        a.bodies()[i].activity != b.bodies()[i].activity)
      return false;
  }
  return true;
}

/// Same bodies, same step, same time (bit for bit).
bool same_bits(const World& a, const World& b) {
  return same_bodies(a, b) && a.step_count() == b.step_count() &&
         std::bit_cast<std::uint64_t>(a.time()) == std::bit_cast<std::uint64_t>(b.time()) &&
         a.settings().integrator == b.settings().integrator;
}

/// The commands the unit tests apply: at step 40 a kick, at 75 the integrator, at 75 a spin.
std::vector<LoggedCommand> script() {
  std::vector<LoggedCommand> out;
  LoggedCommand kick;
  kick.step = 40;
  kick.kind = LoggedKind::impulse;
  kick.body = 3;
  kick.impulse = Vec3(0.0, 2.0, -1.5);
  out.push_back(kick);
  LoggedCommand rk4;
  rk4.step = 75;
  rk4.kind = LoggedKind::integrator;
  rk4.integrator = Integrator::rk4;
  out.push_back(rk4);
  LoggedCommand spin = kick;
  spin.step = 75;
  spin.body = 7;
  spin.impulse = Vec3(0.5, 0.0, 0.0);
  spin.point = Vec3(0.1, 1.0, 0.2);
  out.push_back(spin);
  return out;
}

/// A straight run of `scene` to `steps` with the script applied.
World straight(const Scene& scene, std::uint64_t steps) {
  World w(scene);
  const std::vector<LoggedCommand> commands = script();
  for (;;) {
    for (const LoggedCommand& c : commands)
      if (c.step == w.step_count()) apply_logged(w, c);
    if (w.step_count() == steps) return w;
    w.step();
  }
}

/// Runs `scene` live for `steps` with the script, recording into `timeline`.
void record(Timeline& timeline, World& w, std::uint64_t steps) {
  const std::vector<LoggedCommand> commands = script();
  while (w.step_count() < steps) {
    for (const LoggedCommand& c : commands) {
      if (c.step != w.step_count()) continue;
      apply_logged(w, c);
      timeline.record_command(w, c);
    }
    w.step();
    timeline.record_step(w);
  }
}

TEST(Timeline, RestoreIsBitIdenticalToAStraightRun) {
  const Scene scene = load_scene("dominoes");
  World live(scene);
  Timeline timeline({60.0, 64u << 20});
  timeline.restart(live, "dominoes");
  record(timeline, live, 200);
  ASSERT_TRUE(timeline.enabled());
  ASSERT_EQ(timeline.head().step, 200u);
  for (std::uint64_t k : {0u, 1u, 29u, 30u, 40u, 41u, 75u, 76u, 133u, 200u}) {
    const std::optional<World> restored = timeline.restore(k);
    ASSERT_TRUE(restored) << k;
    EXPECT_TRUE(same_bits(*restored, straight(scene, k))) << "step " << k;
  }
  // Not trivially equal: the next step's bodies differ.
  EXPECT_FALSE(same_bodies(*timeline.restore(100), straight(scene, 101)));
  EXPECT_FALSE(timeline.restore(201));
}

TEST(Timeline, ThinnedCheckpointsStillRestoreExactlyAndStayUnderTheBound) {
  const Scene scene = load_scene("dominoes");
  World live(scene);
  const std::size_t one = estimate_world_bytes(live);
  Timeline timeline({1e6, one * 12});  // Room for a dozen checkpoints of a 60-step interval.
  timeline.restart(live, "dominoes");
  record(timeline, live, 3000);
  EXPECT_LE(timeline.bytes(), timeline.bytes_limit());
  const TimelineSummary s = timeline.summary();
  EXPECT_GT(s.interval, 30u) << "the interval widened";
  EXPECT_EQ(s.from.step, 0u) << "thinning keeps the oldest checkpoint";
  for (std::uint64_t k : {0u, 40u, 1234u, 2999u}) {
    const std::optional<World> restored = timeline.restore(k);
    ASSERT_TRUE(restored) << k;
    EXPECT_TRUE(same_bits(*restored, straight(scene, k))) << "step " << k;
  }
}

TEST(Timeline, DiscardFutureForgetsLaterCommands) {
  const Scene scene = load_scene("dominoes");
  World live(scene);
  Timeline timeline({60.0, 64u << 20});
  timeline.restart(live, "dominoes");
  record(timeline, live, 120);
  World past = *timeline.restore(50);
  timeline.discard_future(past);
  EXPECT_EQ(timeline.head().step, 50u);
  for (const LoggedCommand& c : timeline.summary().commands) EXPECT_LE(c.step, 50u);
  EXPECT_FALSE(timeline.restore(51));
}

// A recording's JSON (scene with random orientations, impulses at points) reads back to the
// same run: the replay ends on the live world's digest.
TEST(Timeline, RecordingJsonRoundTripsToTheSameDigest) {
  Scene pile = load_scene("pile");
  pile.bodies.resize(tumble::testing::kPileBodies);
  World live(pile);
  Timeline timeline({60.0, 256u << 20});
  timeline.restart(live, "pile");
  record(timeline, live, 90);
  const std::optional<Recording> r = timeline.recording(live);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->digest, state_digest(live));
  const Recording back = parse_recording(json::parse(recording_json(*r).dump()));
  const ReplayResult replayed = replay(back, 2);
  EXPECT_EQ(replayed.step, 90u);
  EXPECT_EQ(digest_hex(replayed.digest), digest_hex(state_digest(live)));
  // The digest sees a tiny change of one impulse (1e-9 N·s sideways on a 2.5 N·s kick).
  Recording nudged = back;
  const auto kick = std::find_if(nudged.commands.begin(), nudged.commands.end(),
                                 [](const LoggedCommand& c) { return c.kind == LoggedKind::impulse; });
  ASSERT_NE(kick, nudged.commands.end());
  kick->impulse.x() += 1e-9;  // sideways: a vertical one can end exactly undone by the floor
  EXPECT_NE(replay(nudged).digest, replayed.digest);
}

// The byte bound is only as good as the estimate of a World copy: compared here with what
// the heap grows by when the pile (1000 boxes, landing: the most contacts) is copied.
TEST(Timeline, CheckpointEstimateCoversTheHeapACopyTakes) {
  World world(load_scene("pile"));
  for (int i = 0; i < 150; ++i) world.step();
  const std::size_t estimate = estimate_world_bytes(world);
  // Chunks from the heap and chunks mapped on their own: glibc maps a block above its mmap
  // threshold (128 KiB at first, raised as mapped blocks are freed), so where the contact
  // cache's ~1.5 MB lands depends on what the steps before freed.
  auto in_use = [] {
    const struct mallinfo2 m = mallinfo2();
    return m.uordblks + m.hblkhd;
  };
  const std::size_t before = in_use();
  std::optional<World> copy(world);
  const std::size_t taken = in_use() - before;
  std::printf("pile at step 150: a copy takes %zu bytes, estimated %zu\n", taken, estimate);
  EXPECT_GE(estimate, taken);
  EXPECT_LE(estimate, 3 * taken) << "an estimate far above the truth wastes the bound";
}

// ---- Through the server ---------------------------------------------------------------

class TimelineServerTest : public WorldApiTest {
 protected:
  Scene initial_scene() override { return load_scene("dominoes"); }
  void configure(ServerOptions& o) override { o.read_budget = 0; }

  /// Steps `n` steps exactly (POST step may stop at its budget: it is repeated).
  void step(const std::string& world, std::uint64_t n) {
    const std::uint64_t target = get(world, "state")["step"].get<std::uint64_t>() + n;
    for (int i = 0; i < 1000; ++i) {
      const std::uint64_t at = get(world, "state")["step"];
      if (at >= target) return;
      ok(world, "step", json{{"steps", std::min<std::uint64_t>(target - at, 100000)}}.dump());
    }
    FAIL() << "could not step";
  }
  /// A fresh paused run of the world's scene at step 0.
  void fresh(const std::string& world) {
    ok(world, "pause");
    ok(world, "reset");
    ASSERT_EQ(get(world, "state")["step"], 0);
  }
  /// Creates a second world of the same scene (the straight run).
  void create(const std::string& id) {
    const HttpReply r =
        http_request(port_, boost::beast::http::verb::put, "/api/worlds/" + id, R"({"scene": "dominoes"})");
    ASSERT_EQ(r.status, 201u) << r.body;
    tokens_[id] = r.json()["token"];
  }
  /// The parts of /api/state that are the world's state (time, step, bodies), not the loop's.
  json physical(const std::string& world) {
    const json s = get(world, "state");
    return {{"time", s["time"]}, {"step", s["step"]}, {"bodies", s["bodies"]}};
  }
  static std::string kick(int body, double y) {
    return json{{"body", body}, {"impulse", {0.3, y, -0.2}}, {"point", {0.0, 1.0, 0.1}}}.dump();
  }

};

TEST_F(TimelineServerTest, SeekShowsExactlyTheStraightRun) {
  fresh("default");
  step("default", 90);
  ok("default", "impulse", kick(2, 3.0));
  step("default", 60);
  ok("default", "integrator", R"({"integrator": "rk4"})");
  step("default", 60);
  ok("default", "impulse", kick(5, 2.0));
  step("default", 100);
  const json head = physical("default");
  ASSERT_EQ(head["step"], 310);

  const json seek = ok("default", "seek", R"({"step": 150})");
  EXPECT_EQ(seek["step"], 150);
  const json past = physical("default");
  EXPECT_NE(past, head);
  const json h = get("default", "history");
  EXPECT_FALSE(h["live"]);
  EXPECT_TRUE(h["paused"]);
  EXPECT_EQ(h["at"]["step"], 150);
  EXPECT_EQ(h["to"]["step"], 310) << "the future stays recorded";
  EXPECT_EQ(h["from"]["step"], 0);

  create("ref");
  fresh("ref");
  step("ref", 90);
  ok("ref", "impulse", kick(2, 3.0));
  step("ref", 60);
  EXPECT_EQ(physical("ref"), past) << "seek to 150 differs from the straight run";

  // By time: the step nearest, and the state equal to the straight run's at that step.
  ok("ref", "integrator", R"({"integrator": "rk4"})");
  step("ref", 60);
  ok("ref", "impulse", kick(5, 2.0));  // The state at a step includes that step's commands.
  const double t210 = get("ref", "state")["time"];
  const json by_time = ok("default", "seek", json{{"time", t210}}.dump());
  EXPECT_EQ(by_time["step"], 210);
  EXPECT_EQ(physical("default"), physical("ref"));
  // And forward to the head again.
  ok("default", "seek", R"({"step": 310})");
  EXPECT_EQ(physical("default"), head);
  EXPECT_TRUE(get("default", "history")["live"]);
}

TEST_F(TimelineServerTest, ResumeFromThePastEqualsAFreshRunWithTheSameCommands) {
  fresh("default");
  step("default", 100);
  ok("default", "impulse", kick(1, 2.5));
  step("default", 100);
  ok("default", "impulse", kick(4, 4.0));  // At 200: in the future that is discarded.
  step("default", 50);
  ok("default", "seek", R"({"step": 120})");
  ok("default", "impulse", kick(7, 1.0));  // A change at 120: the future is gone.
  json h = get("default", "history");
  EXPECT_EQ(h["to"]["step"], 120);
  EXPECT_TRUE(h["live"]);
  for (const json& c : h["commands"]) EXPECT_LE(c["step"].get<int>(), 120) << c;
  step("default", 80);
  ok("default", "resume");
  std::this_thread::sleep_for(200ms);
  ok("default", "pause");
  const std::uint64_t end = get("default", "state")["step"];
  ASSERT_GT(end, 200u);

  create("ref");
  fresh("ref");
  step("ref", 100);
  ok("ref", "impulse", kick(1, 2.5));
  step("ref", 20);
  ok("ref", "impulse", kick(7, 1.0));
  step("ref", end - 120);
  EXPECT_EQ(physical("default"), physical("ref"));

  // Resume from a seek: "resume from here" discards what came after.
  ok("default", "seek", R"({"step": 150})");
  ok("default", "resume");
  ok("default", "pause");
  h = get("default", "history");
  EXPECT_TRUE(h["live"]);
  EXPECT_LT(h["to"]["step"].get<std::uint64_t>(), end) << "the old future was discarded";
  bool resumed_at_150 = false;
  for (const json& c : h["commands"])
    resumed_at_150 |= c["kind"] == "resume" && c["step"] == 150;
  EXPECT_TRUE(resumed_at_150) << h["commands"];
}

TEST_F(TimelineServerTest, PlayReplaysTheRecordedFutureThenGoesLive) {
  fresh("default");
  step("default", 60);
  ok("default", "impulse", kick(3, 3.0));
  step("default", 140);
  ok("default", "seek", R"({"step": 30})");
  const json played = ok("default", "play", R"({"speed": 4})");
  EXPECT_TRUE(played["playing"]);
  EXPECT_EQ(played["speed"], 4.0);
  json h;
  for (int i = 0; i < 100; ++i) {
    h = get("default", "history");
    if (h["live"]) break;
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_TRUE(h["live"]) << h;
  EXPECT_FALSE(h["playing"]);
  EXPECT_EQ(h["speed"], 1.0) << "live again at 1x";
  ok("default", "pause");
  const std::uint64_t end = get("default", "state")["step"];
  ASSERT_GE(end, 200u);
  bool kept = false;
  const json after = get("default", "history");
  for (const json& c : after["commands"]) kept |= c["kind"] == "impulse" && c["step"] == 60;
  EXPECT_TRUE(kept) << "playback does not change the log: " << after;

  create("ref");
  fresh("ref");
  step("ref", 60);
  ok("ref", "impulse", kick(3, 3.0));
  step("ref", end - 60);
  EXPECT_EQ(physical("default"), physical("ref"));
}

TEST_F(TimelineServerTest, SpeedSetsTheRealTimeFactor) {
  ok("default", "resume");
  const json set = ok("default", "speed", R"({"speed": 0.25})");
  EXPECT_EQ(set["speed"], 0.25);
  EXPECT_EQ(get("default", "state")["speed"], 0.25);
  const double t0 = get("default", "state")["time"];
  std::this_thread::sleep_for(1s);
  const double t1 = get("default", "state")["time"];
  EXPECT_GT(t1 - t0, 0.1);
  EXPECT_LT(t1 - t0, 0.6) << "a quarter of real time";
  EXPECT_EQ(get("default", "history")["speed"], 0.25);
}

TEST_F(TimelineServerTest, BadInputIsRefusedNamingTheField) {
  fresh("default");
  step("default", 30);
  const auto refused = [&](const std::string& route, const std::string& body, const char* field) {
    const HttpReply r = post("default", route, body);
    EXPECT_EQ(r.status, 400u) << route << ' ' << body << ": " << r.body;
    EXPECT_EQ(r.json()["field"], field) << route << ' ' << body << ": " << r.body;
  };
  refused("seek", R"({"step": 31})", "step");
  refused("seek", R"({"step": -1})", "step");
  refused("seek", R"({"time": -5})", "time");
  refused("seek", R"({"time": 1e9})", "time");
  refused("seek", R"({"time": "soon"})", "time");
  refused("seek", R"({})", "time");
  refused("seek", R"({"time": 0.1, "step": 2})", "step");
  refused("seek", R"({"when": 1})", "when");
  refused("speed", R"({"speed": 0})", "speed");
  refused("speed", R"({"speed": 4.5})", "speed");
  refused("speed", R"({"speed": "fast"})", "speed");
  refused("speed", R"({})", "speed");
  refused("play", R"({"speed": 0.1})", "speed");
  refused("play", R"({"speed": 8})", "speed");
  // The world is untouched and still answers.
  EXPECT_EQ(get("default", "state")["step"], 30);
  EXPECT_EQ(ok("default", "seek", R"({"step": 10})")["step"], 10);
}

TEST_F(TimelineServerTest, TheStreamStatusSaysLivePlayingAndSpeed) {
  fresh("default");
  step("default", 120);
  WsClient viewer(port_);
  const auto status_where = [&](const std::function<bool(const json&)>& wanted) {
    for (int i = 0; i < 400; ++i) {
      const std::optional<WsClient::Message> m = viewer.read(3s);
      if (!m) return json();
      if (!m->text) continue;
      const json j = json::parse(m->data);
      if (j["type"] == "status" && wanted(j)) return j;
    }
    return json();
  };
  EXPECT_TRUE(status_where([](const json& j) { return j["live"] == true; }).is_object());
  ok("default", "seek", R"({"step": 40})");
  const json past = status_where([](const json& j) { return j["live"] == false; });
  ASSERT_TRUE(past.is_object()) << "no status with live false after a seek";
  EXPECT_EQ(past["step"], 40);
  EXPECT_FALSE(past["playing"]);
  ok("default", "play", R"({"speed": 0.5})");
  const json playing = status_where([](const json& j) { return j["playing"] == true; });
  ASSERT_TRUE(playing.is_object());
  EXPECT_EQ(playing["speed"], 0.5);
}

class HistoryOffTest : public TimelineServerTest {
  void configure(ServerOptions& o) override { o.history_s = 0; }
};

TEST_F(HistoryOffTest, SeekAndRecordingAnswer409) {
  const json h = get("default", "history");
  EXPECT_FALSE(h["enabled"]);
  EXPECT_EQ(post("default", "seek", R"({"step": 0})").status, 409u);
  EXPECT_EQ(http_get(port_, "/api/recording").status, 409u);
}

// ---- Memory over ten minutes of the pile ------------------------------------------------

class PileHistoryTest : public TimelineServerTest {
 protected:
  Scene initial_scene() override { return load_scene("pile"); }
  void configure(ServerOptions& o) override {
    o.read_budget = 0;
    o.history_mb = 24;
    o.step_budget_ms = 1500;  // Each POST step answers well within the client's 5 s.
  }
};

TEST_F(PileHistoryTest, StaysUnderItsBoundOverTenMinutes) {
  fresh("default");
  const double dt = get("default", "scene")["dt"];
  const auto steps = static_cast<std::uint64_t>(std::llround(600.0 / dt));
  std::size_t peak = 0;
  for (std::uint64_t done = 0; done < steps;) {
    const std::uint64_t chunk = std::min<std::uint64_t>(steps - done, 300);
    step("default", chunk);
    done += chunk;
    if (done % 7200 == 0) ok("default", "impulse", kick(static_cast<int>(done / 7200), 5.0));
    const json h = get("default", "history");
    ASSERT_TRUE(h["enabled"]) << h;
    const std::size_t bytes = h["bytes"];
    peak = std::max(peak, bytes);
    ASSERT_LE(bytes, h["bytes_limit"].get<std::size_t>()) << "after " << done << " steps";
    const double from = h["from"]["time"], to = h["to"]["time"];
    EXPECT_LE(to - from, 60.0 + 60.0 * 0.5 + 1e-9) << "the window is --history-s";
    if (to > 90.0) {
      EXPECT_GE(to - from, 30.0) << "thinning keeps most of the window";
    }
  }
  const json h = get("default", "history");
  std::printf("pile, 10 min: %zu checkpoints every %d steps, peak %.1f MiB of %.1f\n",
              h["checkpoints"].get<std::size_t>(), h["checkpoint_interval"].get<int>(),
              static_cast<double>(peak) / (1 << 20),
              h["bytes_limit"].get<double>() / (1 << 20));
  // The oldest step is still reachable.
  EXPECT_EQ(ok("default", "seek", json{{"step", h["from"]["step"]}}.dump())["step"],
            h["from"]["step"]);
}

// ---- Recordings replayed by tumble-sim --------------------------------------------------

class RecordingTest : public TimelineServerTest {
 protected:
  /// Runs tumble-sim --replay on `text` written to a file: (exit code, output).
  std::pair<int, std::string> replay(const std::string& text) {
    const std::filesystem::path file = dir_ / "recording.json";
    write_file(file, text);
    ChildProcess sim({TUMBLE_SIM_BINARY, "--replay", file.string(), "--threads", "2"});
    std::string out = sim.rest();
    return {sim.wait(), out};
  }
};

TEST_F(RecordingTest, AServerRecordingReplaysToTheSameDigest) {
  ok("default", "resume");
  for (int i = 0; i < 4; ++i) {
    std::this_thread::sleep_for(150ms);
    ok("default", "impulse", kick(i * 3, 2.0 + i));
  }
  ok("default", "integrator", R"({"integrator": "splitting"})");
  std::this_thread::sleep_for(150ms);
  ok("default", "pause");
  const HttpReply r = http_get(port_, "/api/recording");
  ASSERT_EQ(r.status, 200u) << r.body;
  const json recording = r.json();
  EXPECT_EQ(recording["format"], "tumble-recording");
  EXPECT_EQ(recording["final_step"], get("default", "state")["step"]);
  int impulses = 0;
  for (const json& c : recording["commands"]) impulses += c["kind"] == "impulse";
  EXPECT_EQ(impulses, 4);

  auto [code, out] = replay(recording.dump());
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("\"match\":true"), std::string::npos) << out;
  EXPECT_NE(out.find(recording["digest"].get<std::string>()), std::string::npos) << out;

  // A changed impulse is a different run: exit 1.
  json changed = recording;
  for (json& c : changed["commands"])
    if (c["kind"] == "impulse") {
      c["impulse"][1] = c["impulse"][1].get<double>() + 1e-9;
      break;
    }
  std::tie(code, out) = replay(changed.dump());
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("\"match\":false"), std::string::npos) << out;

  // A recording of a past step (after a seek) replays too.
  const std::uint64_t half = recording["final_step"].get<std::uint64_t>() / 2;
  ok("default", "seek", json{{"step", half}}.dump());
  const json past = http_get(port_, "/api/recording").json();
  EXPECT_EQ(past["final_step"], half);
  std::tie(code, out) = replay(past.dump());
  EXPECT_EQ(code, 0) << out;
}

TEST_F(RecordingTest, AMalformedFileExits2NamingTheField) {
  const json good = http_get(port_, "/api/recording").json();
  ASSERT_EQ(good["format"], "tumble-recording");
  const auto bad = [&](const json& doc, const std::string& field) {
    auto [code, out] = replay(doc.dump());
    EXPECT_EQ(code, 2) << out;
    EXPECT_NE(out.find("'" + field + "'"), std::string::npos) << field << ": " << out;
  };
  json j = good;
  j.erase("digest");
  bad(j, "digest");
  j = good;
  j["version"] = 99;
  bad(j, "version");
  j = good;
  j["scene"]["bodies"][0]["mass"] = -1;
  bad(j, "scene.bodies[0].mass");
  j = good;
  j["commands"].push_back({{"step", 0}, {"kind", "impulse"}, {"body", 999}, {"impulse", {0, 1, 0}}});
  bad(j, "commands[" + std::to_string(good["commands"].size()) + "].body");
  j = good;
  j["commands"].push_back({{"step", 0}, {"kind", "explode"}});
  bad(j, "commands[" + std::to_string(good["commands"].size()) + "].kind");
  auto [code, out] = replay("{not json");
  EXPECT_EQ(code, 2) << out;
}

}  // namespace
}  // namespace tumble::server::test
