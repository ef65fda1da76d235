// POST …/bodies (docs/protocol.md, "Bodies") and the WebSocket contacts overlay ("WebSocket",
// "contacts"), through a real server on 127.0.0.1: an added body falls and lands, refusals
// name the field, --max-bodies bounds it, the timeline and recordings reproduce it exactly,
// and only a viewer that asks receives contact points.
#include <gtest/gtest.h>

#include <filesystem>
#include <thread>

#include "child_process.hpp"
#include "server_fixture.hpp"
#include "world_api_test_base.hpp"

namespace tumble::server::test {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

class BodiesTest : public WorldApiTest {
 protected:
  Scene initial_scene() override { return load_scene("resting"); }
  void configure(ServerOptions& o) override { o.read_budget = 0; }

  /// Adds a body, expecting 201.
  json add(const std::string& world, const json& body) {
    const HttpReply r = post(world, "bodies", body.dump());
    EXPECT_EQ(r.status, 201u) << body << ": " << r.body;
    return r.json();
  }
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
  /// The world's state (time, step, bodies), not the loop's.
  json physical(const std::string& world) {
    const json s = get(world, "state");
    return {{"time", s["time"]}, {"step", s["step"]}, {"bodies", s["bodies"]}};
  }
  /// A 0.5 m box of 2 kg, 3 m above the floor away from the scene's boxes.
  static json box(double x = 0.0, double z = 3.0) {
    return {{"size", {0.5, 0.5, 0.5}},
            {"mass", 2.0},
            {"position", {x, 3.0, z}},
            {"velocity", {0.1, 0.0, -0.05}},
            {"angular_velocity", {0.0, 1.0, 0.5}}};
  }
  /// tumble-sim --replay on `text`: (exit code, output).
  std::pair<int, std::string> replay(const std::string& text) {
    const std::filesystem::path file = dir_ / "recording.json";
    write_file(file, text);
    ChildProcess sim({TUMBLE_SIM_BINARY, "--replay", file.string(), "--threads", "2"});
    std::string out = sim.rest();
    return {sim.wait(), out};
  }

};

TEST_F(BodiesTest, AnAddedBodyIsListedFallsAndLands) {
  fresh("default");
  const std::size_t n = state()["bodies"].size();
  const json added = add("default", box());
  EXPECT_EQ(added["ok"], true);
  EXPECT_EQ(added["body"], n);
  EXPECT_EQ(added["name"], "box-" + std::to_string(n));
  json s = state();
  ASSERT_EQ(s["bodies"].size(), n + 1);
  EXPECT_EQ(s["bodies"][n]["name"], added["name"]);
  EXPECT_DOUBLE_EQ(s["bodies"][n]["position"][1].get<double>(), 3.0);
  // The scene viewers load lists it too.
  const json scene = get("default", "scene");
  ASSERT_EQ(scene["bodies"].size(), n + 1);
  EXPECT_EQ(scene["bodies"][n]["mass"], 2.0);
  // A named one keeps its name; the next default name skips taken ones.
  json named = box(3.0, 3.0);
  named["name"] = "crate";
  named["color"] = "#123456";
  EXPECT_EQ(add("default", named)["name"], "crate");

  step("default", 300);  // 5 s: fallen 2.75 m and settled.
  s = state();
  const json& b = s["bodies"][n];
  EXPECT_NEAR(b["position"][1].get<double>(), 0.25, 2e-3) << b;
  EXPECT_LT(std::abs(b["velocity"][1].get<double>()), 0.05) << b;
  EXPECT_NEAR(s["bodies"][n + 1]["position"][1].get<double>(), 0.25, 2e-3);

  // A reset restarts the scene as loaded: the added bodies are gone.
  ok("default", "reset");
  EXPECT_EQ(state()["bodies"].size(), n);
}

TEST_F(BodiesTest, RefusalsNameTheFieldAndTheWorldRunsOn) {
  ok("default", "resume");
  const auto refused = [&](const json& body, const std::string& field) {
    const HttpReply r = post("default", "bodies", body.dump());
    EXPECT_EQ(r.status, 400u) << body << ": " << r.body;
    EXPECT_EQ(r.json()["field"], field) << body << ": " << r.body;
    EXPECT_TRUE(r.json().contains("error")) << r.body;
  };
  json b = box();
  b.erase("mass");
  refused(b, "mass");
  b = box();
  b["mass"] = -1.0;
  refused(b, "mass");
  b = box();
  b["mass"] = "heavy";
  refused(b, "mass");
  b = box();
  b["size"] = {1.0, 2.0};
  refused(b, "size");
  b = box();
  b["size"] = {1.0, 0.0, 1.0};
  refused(b, "size");
  b = box();
  b["colour"] = "#ffffff";
  refused(b, "colour");
  b = box();
  b["velocity"] = {5000.0, 0.0, 0.0};
  refused(b, "velocity");
  b = box();
  b["name"] = "cube";  // The scene's.
  refused(b, "name");
  b = box();
  b["restitution"] = 2.0;
  refused(b, "restitution");
  const HttpReply bad = post("default", "bodies", "[1,2]");
  EXPECT_EQ(bad.status, 400u) << bad.body;
  EXPECT_EQ(state()["bodies"].size(), 3u) << "nothing was added";
  EXPECT_FALSE(state()["paused"]);

  // Another world's route needs that world's token.
  const HttpReply r = http_request(port_, boost::beast::http::verb::put, "/api/worlds/other",
                                   R"({"scene": "resting"})");
  ASSERT_EQ(r.status, 201u) << r.body;
  const HttpReply anonymous = http_post(port_, "/api/worlds/other/bodies", box().dump());
  EXPECT_TRUE(anonymous.status == 401u || anonymous.status == 403u) << anonymous.body;
  tokens_["other"] = r.json()["token"];
  EXPECT_EQ(add("other", box())["body"], 3);
}

class BodiesBoundTest : public BodiesTest {
 protected:
  void configure(ServerOptions& o) override {
    o.read_budget = 0;
    o.max_bodies = 4;  // resting has 3.
  }
};

TEST_F(BodiesBoundTest, MaxBodiesBoundsTheWorld) {
  add("default", box());
  const HttpReply r = post("default", "bodies", box(3.0).dump());
  EXPECT_EQ(r.status, 409u) << r.body;
  EXPECT_EQ(r.json()["field"], "bodies") << r.body;
  EXPECT_EQ(state()["bodies"].size(), 4u);
}

TEST_F(BodiesTest, TheRecordingCarriesTheBodyAndReplaysToTheSameDigest) {
  fresh("default");
  step("default", 30);
  json b = box();
  b["name"] = "crate";
  b["orientation"] = {0.9238795325112867, 0.0, 0.3826834323650898, 0.0};
  b["friction"] = 0.3;
  add("default", b);
  step("default", 45);
  ok("default", "impulse", R"({"body": "crate", "impulse": [1.0, 2.0, 0.0]})");
  add("default", box(-4.0, 2.0));
  step("default", 60);
  const HttpReply r = http_get(port_, "/api/recording");
  ASSERT_EQ(r.status, 200u) << r.body;
  const json recording = r.json();
  EXPECT_EQ(recording["scene"]["bodies"].size(), 3u) << "the scene at step 0";
  std::vector<json> adds;
  for (const json& c : recording["commands"])
    if (c["kind"] == "add_body") adds.push_back(c);
  ASSERT_EQ(adds.size(), 2u) << recording["commands"];
  EXPECT_EQ(adds[0]["step"], 30);
  EXPECT_EQ(adds[0]["body"], 3);
  EXPECT_EQ(adds[0]["definition"]["name"], "crate");
  EXPECT_EQ(adds[0]["definition"]["mass"], 2.0);
  EXPECT_EQ(adds[0]["definition"]["friction"], 0.3);
  EXPECT_EQ(adds[1]["step"], 75);
  EXPECT_EQ(adds[1]["body"], 4);

  auto [code, out] = replay(recording.dump());
  EXPECT_EQ(code, 0) << out;
  EXPECT_NE(out.find("\"match\":true"), std::string::npos) << out;
  EXPECT_NE(out.find(recording["digest"].get<std::string>()), std::string::npos) << out;

  // A different body is a different run; a wrong id is refused, naming the field.
  json changed = recording;
  for (json& c : changed["commands"])
    if (c["kind"] == "add_body") {
      c["definition"]["mass"] = 2.5;
      break;
    }
  std::tie(code, out) = replay(changed.dump());
  EXPECT_EQ(code, 1) << out;
  json wrong = recording;
  for (json& c : wrong["commands"])
    if (c["kind"] == "add_body") {
      c["body"] = 7;
      break;
    }
  std::tie(code, out) = replay(wrong.dump());
  EXPECT_EQ(code, 2) << out;
  EXPECT_NE(out.find(".body"), std::string::npos) << out;
}

TEST_F(BodiesTest, SeekBeforeTheAdditionThenStepReproducesItBitForBit) {
  fresh("default");
  step("default", 40);
  add("default", box());
  step("default", 50);
  ok("default", "impulse", R"({"body": 3, "impulse": [0.5, 1.0, 0.0]})");
  step("default", 60);
  const json head = physical("default");
  ASSERT_EQ(head["step"], 150);
  ASSERT_EQ(head["bodies"].size(), 4u);

  ok("default", "seek", R"({"step": 20})");
  EXPECT_EQ(state()["bodies"].size(), 3u) << "before the addition";
  EXPECT_EQ(get("default", "scene")["bodies"].size(), 3u);
  ok("default", "seek", R"({"step": 40})");
  EXPECT_EQ(state()["bodies"].size(), 4u) << "a step shows its commands";
  ok("default", "seek", R"({"step": 20})");
  step("default", 130);  // Replays the recorded future, the addition included.
  EXPECT_EQ(physical("default"), head);

  // Playback reproduces it too.
  ok("default", "seek", R"({"step": 20})");
  ok("default", "play", R"({"speed": 4})");
  for (int i = 0; i < 100 && get("default", "state")["step"].get<std::uint64_t>() < 150; ++i)
    std::this_thread::sleep_for(50ms);
  ok("default", "pause");
  ok("default", "seek", R"({"step": 150})");
  EXPECT_EQ(physical("default"), head);

  // A body added at a past step discards the recorded future first.
  ok("default", "seek", R"({"step": 20})");
  EXPECT_EQ(add("default", box(3.0))["body"], 3);
  const json h = get("default", "history");
  EXPECT_EQ(h["to"]["step"], 20);
  for (const json& c : h["commands"]) EXPECT_LE(c["step"].get<int>(), 20) << c;
  EXPECT_EQ(state()["bodies"].size(), 4u);
}

// ---- Contacts over the WebSocket ----------------------------------------------------------

/// Contacts messages received within `within` (other messages skipped).
std::vector<json> contact_messages(WsClient& ws, std::chrono::milliseconds within,
                                   std::size_t enough = 1000) {
  std::vector<json> out;
  const auto end = std::chrono::steady_clock::now() + within;
  while (std::chrono::steady_clock::now() < end && out.size() < enough) {
    const auto m = ws.read(200ms);
    if (!m || !m->text) continue;
    json j = json::parse(m->data, nullptr, false);
    if (j.is_object() && j.value("type", "") == "contacts") out.push_back(std::move(j));
  }
  return out;
}

class ContactsTest : public BodiesTest {
 protected:
  Scene initial_scene() override { return load_scene("tower"); }
};

TEST_F(ContactsTest, OnlyAViewerThatAsksReceivesContactPointsOnTheFloor) {
  WsClient asks(port_);
  WsClient never(port_);
  WsClient malformed(port_);
  asks.send_text(R"({"type":"contacts","on":true})");
  malformed.send_text(R"({"type":"contacts","on":1})");
  malformed.send_text(R"({"type":"contacts","on":true,"extra":1})");
  const std::vector<json> got = contact_messages(asks, 3s, 20);
  ASSERT_GE(got.size(), 3u);
  std::uint64_t last_step = 0;
  bool first = true;
  for (const json& m : got) {
    const std::uint64_t step = m["step"];
    if (!first) EXPECT_NE(step, last_step) << "one message per step";
    first = false;
    last_step = step;
    EXPECT_FALSE(m["truncated"]);
    ASSERT_FALSE(m["points"].empty()) << m;
  }
  const json& points = got.back()["points"];
  int on_floor = 0;
  for (const json& p : points) {
    ASSERT_EQ(p.size(), 8u) << p;
    EXPECT_TRUE(p[7] == 0 || p[7] == 1) << p;
    EXPECT_GE(p[6].get<double>(), 0.0) << p;
    if (std::abs(p[1].get<double>()) < 1e-3) {
      ++on_floor;
      EXPECT_NEAR(p[4].get<double>(), 1.0, 1e-3) << "the floor's normal is up: " << p;
    }
  }
  EXPECT_GE(on_floor, 3) << points;  // The tower's base box touches the floor at its corners.

  EXPECT_TRUE(contact_messages(never, 1s).empty()) << "a viewer that never asked";
  EXPECT_TRUE(contact_messages(malformed, 500ms).empty()) << "malformed requests are ignored";

  // Off again: no more contacts.
  asks.send_text(R"({"type":"contacts","on":false})");
  contact_messages(asks, 300ms);  // Drains what was on its way.
  EXPECT_TRUE(contact_messages(asks, 1s).empty());
}

}  // namespace
}  // namespace tumble::server::test
