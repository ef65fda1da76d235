// Worlds (docs/protocol.md, "Worlds"), against a real server on 127.0.0.1: create, list and
// delete; isolation between worlds; write tokens; limits; idle pause and removal; the
// default world as it always was.
#include <gtest/gtest.h>

#include <thread>

#include "server_fixture.hpp"

namespace tumble::server::test {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
namespace http = boost::beast::http;

class WorldsTest : public ServerTest {
 protected:
  void configure(ServerOptions& o) override {
    o.max_worlds = 4;
    o.max_bodies = 500;
    o.idle_s = 60;  // far beyond a test, even a sanitizer build's (IdleWorldsTest shortens it)
    o.idle_remove_s = 120;
  }

  /// PUT /api/worlds/{id} with `scene` (JSON text).
  HttpReply put(const std::string& id, const std::string& scene,
                const std::map<std::string, std::string>& headers = {}) {
    return http_request(port_, http::verb::put, "/api/worlds/" + id, R"({"scene": )" + scene + "}",
                        headers);
  }
  /// Creates world `id` from a bundled scene and returns its token.
  std::string create(const std::string& id, const std::string& scene = "seed") {
    const HttpReply r = put(id, '"' + scene + '"');
    EXPECT_EQ(r.status, 201u) << r.body;
    return r.json().value("token", "");
  }
  static std::map<std::string, std::string> bearer(const std::string& token) {
    return {{"Authorization", "Bearer " + token}};
  }
  HttpReply post(const std::string& id, const std::string& route, const std::string& token,
                 const std::string& body = {}) {
    return http_post(port_, "/api/worlds/" + id + "/" + route, body, bearer(token));
  }
  json world_state(const std::string& id) {
    return http_get(port_, "/api/worlds/" + id + "/state").json();
  }
  json listed(const std::string& id) {
    const HttpReply r = http_get(port_, "/api/worlds");
    if (r.status != 200) ADD_FAILURE() << r.status << ' ' << r.body;
    const json list = r.json();
    for (const json& w : list["worlds"])
      if (w["id"] == id) return w;
    return nullptr;
  }
};

TEST_F(WorldsTest, CreateListDelete) {
  const HttpReply created = put("lab-1", R"("seed")");
  ASSERT_EQ(created.status, 201u) << created.body;
  const std::string token = created.json()["token"];
  EXPECT_EQ(token.size(), 32u);
  EXPECT_EQ(created.json()["scene"], "seed");
  EXPECT_EQ(created.json()["bodies"], 1);
  // The same scene again: the same world, and no token for whoever asks.
  const HttpReply again = put("lab-1", R"("seed")");
  EXPECT_EQ(again.status, 200u) << again.body;
  EXPECT_FALSE(again.json().contains("token"));
  EXPECT_EQ(put("lab-1", R"("many")").status, 409u);

  const json list = http_get(port_, "/api/worlds").json();
  ASSERT_EQ(list["worlds"].size(), 2u) << list;
  EXPECT_EQ(list["worlds"][0]["id"], "default");
  EXPECT_EQ(list["worlds"][1]["id"], "lab-1");
  for (const char* key : {"scene", "bodies", "viewers", "real_time_factor", "paused", "time"})
    EXPECT_TRUE(list["worlds"][1].contains(key)) << key;
  EXPECT_EQ(list["max_worlds"], 4);
  EXPECT_EQ(http_get(port_, "/api/worlds/lab-1").json()["id"], "lab-1");

  EXPECT_EQ(http_request(port_, http::verb::delete_, "/api/worlds/lab-1").status, 401u);
  EXPECT_EQ(http_request(port_, http::verb::delete_, "/api/worlds/lab-1", {}, bearer(token)).status,
            200u);
  EXPECT_EQ(http_get(port_, "/api/worlds/lab-1").status, 404u);
  EXPECT_EQ(http_get(port_, "/api/worlds/lab-1/state").json()["field"], "world");
  EXPECT_TRUE(listed("lab-1").is_null());
  EXPECT_EQ(http_request(port_, http::verb::delete_, "/api/worlds/default").status, 409u);
}

// A reset, a pause or an impulse in one world changes nothing in another, checked by state.
TEST_F(WorldsTest, WorldsAreIsolated) {
  const std::string a = create("a", "pyramid");
  const std::string b = create("b", "pyramid");
  ASSERT_EQ(post("a", "pause", a).status, 200u);
  ASSERT_EQ(post("b", "pause", b).status, 200u);
  const json b0 = world_state("b");
  ASSERT_EQ(post("a", "impulse", a, R"({"body": 0, "impulse": [0, 0, 50]})").status, 200u);
  ASSERT_EQ(post("a", "step", a, R"({"steps": 10})").status, 200u);
  ASSERT_EQ(post("a", "reset", a, R"({"scene": "seed"})").status, 200u);
  ASSERT_EQ(post("a", "resume", a).status, 200u);
  std::this_thread::sleep_for(200ms);
  const json b1 = world_state("b");
  EXPECT_EQ(b1["bodies"], b0["bodies"]) << "world b moved";
  EXPECT_EQ(b1["time"], b0["time"]);
  EXPECT_TRUE(b1["paused"]);
  EXPECT_EQ(world_state("a")["bodies"].size(), 1u) << "a runs the seed scene now";
  EXPECT_FALSE(world_state("a")["paused"]);
  // The default world was not touched either.
  EXPECT_EQ(http_get(port_, "/api/scene").json()["name"], "seed");
  EXPECT_FALSE(state()["paused"]);
}

TEST_F(WorldsTest, WriteTokens) {
  const std::string token = create("t");
  const std::string other = create("u");
  for (const char* route : {"pause", "resume", "reset"})
    EXPECT_EQ(http_post(port_, std::string("/api/worlds/t/") + route).status, 401u) << route;
  EXPECT_EQ(post("t", "pause", other).status, 401u) << "another world's token";
  EXPECT_EQ(post("t", "pause", token).status, 200u);
  EXPECT_EQ(
      http_post(port_, "/api/worlds/t/impulse", R"({"body": 0, "impulse": [1, 0, 0]})").status,
      401u);
  // Reads and viewing stay open.
  EXPECT_EQ(http_get(port_, "/api/worlds/t/state").status, 200u);
  EXPECT_EQ(http_get(port_, "/api/worlds/t/scene").status, 200u);
  WsClient viewer(port_, {}, "/ws?world=t");
  const auto first = viewer.read();
  ASSERT_TRUE(first);
  EXPECT_EQ(json::parse(first->data)["scene"]["name"], "seed");
  EXPECT_EQ(listed("t")["viewers"], 1);
  // The default world keeps its rules: no --token here, so POSTs are open.
  EXPECT_EQ(http_post(port_, "/api/pause").status, 200u);
}

TEST_F(WorldsTest, Limits) {
  create("w1");
  create("w2");
  create("w3");  // With the default: 4 = --max-worlds.
  const HttpReply full = put("w4", R"("seed")");
  EXPECT_EQ(full.status, 429u) << full.body;
  EXPECT_NE(full.json()["error"].get<std::string>().find("max-worlds"), std::string::npos);
  // A deleted world frees its place.
  const std::string token = http_get(port_, "/api/worlds/w1").status == 200 ? "" : "missing";
  EXPECT_EQ(token, "");
  EXPECT_EQ(http_get(port_, "/api/worlds").json()["worlds"].size(), 4u);
}

TEST_F(WorldsTest, BadRequestsNameTheField) {
  const HttpReply pile = put("big", R"("pile")");  // 1,000 bodies > --max-bodies 500
  EXPECT_EQ(pile.status, 400u) << pile.body;
  EXPECT_EQ(pile.json()["field"], "scene.bodies");
  EXPECT_EQ(put("Upper", R"("seed")").json()["field"], "id");
  EXPECT_EQ(put(std::string(65, 'a'), R"("seed")").status, 400u);
  EXPECT_EQ(put("x", R"("no-such-scene")").status, 404u);
  EXPECT_EQ(put("x", R"(42)").json()["field"], "scene");
  EXPECT_EQ(http_request(port_, http::verb::put, "/api/worlds/x", "{}").json()["field"], "scene");
  EXPECT_EQ(http_get(port_, "/api/worlds/x/nothing").status, 404u);
  EXPECT_EQ(http_post(port_, "/api/worlds").status, 405u);
  // A reset of the default world is held to --max-bodies too; the world runs on unchanged.
  const HttpReply reset = http_post(port_, "/api/reset", R"({"scene": "pile"})");
  EXPECT_EQ(reset.status, 400u);
  EXPECT_EQ(reset.json()["field"], "scene.bodies");
  EXPECT_EQ(http_get(port_, "/api/scene").json()["name"], "seed");
  // An unknown world on the socket: 404 before the upgrade.
  EXPECT_THROW(WsClient(port_, {}, "/ws?world=nope"), boost::system::system_error);
  EXPECT_EQ(http_get(port_, "/api/worlds").json()["worlds"].size(), 1u) << "nothing was created";
}

// Idleness in test time: paused after 0.4 s, removed after 1.2 s.
class IdleWorldsTest : public WorldsTest {
 protected:
  void configure(ServerOptions& o) override {
    WorldsTest::configure(o);
    o.idle_s = 0.4;
    o.idle_remove_s = 1.2;
  }
};

// No viewer and no request for --idle-s: paused; for --idle-remove-s: removed. A viewer keeps
// a world alive; the default world never idles out.
TEST_F(IdleWorldsTest, IdleWorldsPauseThenGo) {
  create("idle");
  create("watched");
  WsClient viewer(port_, {}, "/ws?world=watched");
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  bool paused = false;
  while (!paused && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(100ms);
    const json w = listed("idle");
    paused = !w.is_null() && w["paused"] == true;
    viewer.read(10ms);
  }
  EXPECT_TRUE(paused) << "the idle world was not paused";
  while (!listed("idle").is_null() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(100ms);
    viewer.read(10ms);
  }
  EXPECT_TRUE(listed("idle").is_null()) << "the idle world was not removed";
  ASSERT_FALSE(listed("watched").is_null()) << "a watched world was removed";
  EXPECT_FALSE(listed("watched")["paused"]);
  EXPECT_FALSE(state()["paused"]) << "the default world idled";
  EXPECT_NE(http_get(port_, "/metrics").body.find("tumble_world_viewers{world=\"watched\"} 1"),
            std::string::npos);
}

// A request to an idle-paused world wakes it.
TEST_F(IdleWorldsTest, ARequestWakesAnIdleWorld) {
  create("sleepy");
  const auto deadline = std::chrono::steady_clock::now() + 3s;
  while (listed("sleepy")["paused"] != true && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(50ms);
  ASSERT_EQ(listed("sleepy")["paused"], true);
  EXPECT_EQ(http_get(port_, "/api/worlds/sleepy/state").status, 200u);
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(listed("sleepy")["paused"], false);
}

// A world whose request is still running is not idle: a POST /api/step that runs past
// --idle-remove-s (spinning boxes under a 2.5 s step budget) keeps its world, and answers.
class WorldsWithBigScenes : public IdleWorldsTest {
 protected:
  void configure(ServerOptions& o) override {
    IdleWorldsTest::configure(o);
    o.max_bodies = 2000;
    o.step_budget_ms = 2500;  // past --idle-remove-s (1.2 s), within the client's 5 s
  }

  /// 1,000 spinning 1×2×3 m boxes 4 m apart, no gravity and no floor: they never touch and
  /// never sleep, so every step costs the same (~0.15 ms) and 100,000 steps outlast the step
  /// budget however fast the engine gets. (The bundled pile falls asleep within ~400 steps;
  /// its 100,000 steps then took 1.2–1.3 s, too close to --idle-remove-s.)
  static std::string spinning_boxes() {
    json bodies = json::array();
    for (int i = 0; i < 1000; ++i) {
      bodies.push_back({{"name", "b" + std::to_string(i)},
                        {"size", {1, 2, 3}},
                        {"position", {4.0 * (i % 10), 4.0 * (i / 10 % 10), 4.0 * (i / 100)}},
                        {"angular_velocity", {0.3 + 0.001 * i, 1.0, -0.5}}});
    }
    return json{{"name", "spinning"}, {"gravity", {0, 0, 0}}, {"floor", nullptr},
                {"dt", 1.0 / 60.0},   {"bodies", bodies}}
        .dump();
  }
};

TEST_F(WorldsWithBigScenes, ALongRequestKeepsItsWorld) {
  const HttpReply created = put("busy", spinning_boxes());
  ASSERT_EQ(created.status, 201u) << created.body;
  const std::string token = created.json().value("token", "");
  ASSERT_EQ(post("busy", "pause", token).status, 200u);
  const auto t0 = std::chrono::steady_clock::now();
  const HttpReply r = post("busy", "step", token, R"({"steps": 100000})");
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(r.status, 200u) << r.body;
  EXPECT_GT(r.json()["steps_done"].get<int>(), 0);
  EXPECT_GT(took, 1.2) << "the step ended before --idle-remove-s: nothing was shown";
  EXPECT_FALSE(listed("busy").is_null()) << "removed while its step ran";
  EXPECT_EQ(listed("busy")["paused"], true);
}

// A world its user paused is not resumed by a later request.
TEST_F(IdleWorldsTest, AUserPauseOutlastsIdleness) {
  const std::string token = create("held");
  ASSERT_EQ(post("held", "pause", token).status, 200u);
  std::this_thread::sleep_for(700ms);  // past --idle-s
  EXPECT_EQ(http_get(port_, "/api/worlds/held/state").status, 200u);
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(listed("held")["paused"], true);
}

// With --token the server's token creates worlds and steers every world.
class WorldsWithServerToken : public WorldsTest {
  void configure(ServerOptions& o) override {
    WorldsTest::configure(o);
    o.token = "server-secret";
  }
};

TEST_F(WorldsWithServerToken, TheServerTokenCreatesAndSteers) {
  EXPECT_EQ(put("v", R"("seed")").status, 401u);
  const HttpReply r = put("v", R"("seed")", bearer("server-secret"));
  ASSERT_EQ(r.status, 201u);
  const std::string token = r.json()["token"];
  EXPECT_EQ(post("v", "pause", "server-secret").status, 200u);
  EXPECT_EQ(post("v", "resume", token).status, 200u);
  EXPECT_EQ(http_post(port_, "/api/pause", {}, bearer(token)).status, 401u)
      << "a world's token does not steer the default world";
}

}  // namespace
}  // namespace tumble::server::test
