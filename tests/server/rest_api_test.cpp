// The REST routes of docs/protocol.md against a real server.
#include <gtest/gtest.h>

#include "server_fixture.hpp"

namespace tumble::server::test {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;

class RestApi : public ServerTest {};

void expect_error(const HttpReply& r, unsigned status, const std::string& field) {
  EXPECT_EQ(r.status, status) << r.body;
  const json j = r.json();
  ASSERT_TRUE(j.is_object()) << r.body;
  EXPECT_TRUE(j["error"].is_string()) << r.body;
  EXPECT_EQ(j["field"], field) << r.body;
  EXPECT_EQ(r.headers[boost::beast::http::field::content_type], "application/json");
}

TEST_F(RestApi, Health) {
  const HttpReply r = http_get(port_, "/api/health");
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.json(), (json{{"status", "ok"}}));
  EXPECT_EQ(r.headers[boost::beast::http::field::content_type], "application/json");
}

TEST_F(RestApi, ScenesAndScene) {
  const json scenes = http_get(port_, "/api/scenes").json()["scenes"];
  ASSERT_TRUE(scenes.is_array());
  EXPECT_NE(std::find(scenes.begin(), scenes.end(), "seed"), scenes.end());
  const HttpReply r = http_get(port_, "/api/scene");
  EXPECT_EQ(r.status, 200u);
  // The same JSON as a scene file: it reads back as the running scene.
  const Scene scene = scene_from_json(r.json());
  EXPECT_EQ(scene.world.name, "seed");
  EXPECT_EQ(scene.bodies.size(), 1u);
}

TEST_F(RestApi, StateHasTheDocumentedShape) {
  const json s = state();
  for (const char* key : {"time", "step", "paused", "real_time_factor", "energy", "integrator"})
    EXPECT_TRUE(s.contains(key)) << key;
  EXPECT_EQ(s["integrator"], "midpoint");
  ASSERT_EQ(s["bodies"].size(), 1u);
  const json& b = s["bodies"][0];
  EXPECT_EQ(b["name"], "box");
  EXPECT_EQ(b["position"].size(), 3u);
  EXPECT_EQ(b["orientation"].size(), 4u);
  EXPECT_EQ(b["velocity"].size(), 3u);
  EXPECT_EQ(b["angular_velocity"].size(), 3u);
  EXPECT_TRUE(b["asleep"].is_boolean());
  EXPECT_TRUE(b["frozen"].is_boolean());
}

TEST_F(RestApi, PauseResumeAndStep) {
  EXPECT_EQ(http_post(port_, "/api/pause").json(), (json{{"ok", true}, {"paused", true}}));
  EXPECT_EQ(http_post(port_, "/api/pause").json(), (json{{"ok", true}, {"paused", true}}));
  const json before = state();
  EXPECT_TRUE(before["paused"].get<bool>());
  EXPECT_EQ(before["real_time_factor"], 0.0);
  const HttpReply r = http_post(port_, "/api/step", R"({"steps": 3})");
  ASSERT_EQ(r.status, 200u) << r.body;
  EXPECT_EQ(r.json()["step"], before["step"].get<int>() + 3);
  EXPECT_NEAR(r.json()["time"].get<double>(), before["time"].get<double>() + 3.0 / 30.0, 1e-9);
  EXPECT_EQ(state()["step"], before["step"].get<int>() + 3);
  EXPECT_EQ(http_post(port_, "/api/resume").json(), (json{{"ok", true}, {"paused", false}}));
  EXPECT_EQ(http_post(port_, "/api/resume").json(), (json{{"ok", true}, {"paused", false}}));
  expect_error(http_post(port_, "/api/step", R"({"steps": 1})"), 409, "steps");
}

TEST_F(RestApi, StepValidatesItsInput) {
  http_post(port_, "/api/pause");
  for (const char* body : {R"({"steps": 0})", R"({"steps": 100001})", R"({"steps": -1})",
                           R"({"steps": 1.5})", R"({"steps": "2"})", R"({"steps": 1e999})",
                           R"({})", R"({"steps": 1, "extra": 2})"}) {
    const HttpReply r = http_post(port_, "/api/step", body);
    EXPECT_EQ(r.status, 400u) << body;
  }
  expect_error(http_post(port_, "/api/step", R"({"steps": 0})"), 400, "steps");
  expect_error(http_post(port_, "/api/step", R"({"steps": 1, "extra": 2})"), 400, "extra");
  expect_error(http_post(port_, "/api/step", R"({"steps": )"), 400, "");
  expect_error(http_post(port_, "/api/step", R"([1])"), 400, "");
}

TEST_F(RestApi, ImpulseChangesTheVelocity) {
  http_post(port_, "/api/pause");
  const json v0 = state()["bodies"][0]["velocity"];
  HttpReply r = http_post(port_, "/api/impulse", R"({"body": "box", "impulse": [2, 0, 0]})");
  ASSERT_EQ(r.status, 200u) << r.body;
  EXPECT_EQ(r.json(), (json{{"ok", true}}));
  json v1 = state()["bodies"][0]["velocity"];
  EXPECT_NEAR(v1[0].get<double>() - v0[0].get<double>(), 2.0, 1e-12);  // m = 1 kg
  const json p = state()["bodies"][0]["position"];
  r = http_post(port_, "/api/impulse",
                json{{"body", 0}, {"impulse", {0, 0, 1}}, {"point", p}}.dump());
  ASSERT_EQ(r.status, 200u) << r.body;
  v1 = state()["bodies"][0]["velocity"];
  EXPECT_NEAR(v1[2].get<double>() - v0[2].get<double>(), 1.0, 1e-12);
}

TEST_F(RestApi, ImpulseRefusals) {
  expect_error(http_post(port_, "/api/impulse", R"({"body": "nobody", "impulse": [0, 1, 0]})"),
               404, "body");
  expect_error(http_post(port_, "/api/impulse", R"({"body": 1, "impulse": [0, 1, 0]})"), 404,
               "body");
  expect_error(http_post(port_, "/api/impulse", R"({"body": -1, "impulse": [0, 1, 0]})"), 404,
               "body");
  // Numbers beyond a double's range never become infinities: the JSON reader refuses them.
  expect_error(http_post(port_, "/api/impulse", R"({"body": 0, "impulse": [0, 1e999, 0]})"), 400,
               "");
  expect_error(http_post(port_, "/api/impulse", R"({"body": 0, "impulse": [0, 1]})"), 400,
               "impulse");
  expect_error(http_post(port_, "/api/impulse", R"({"body": 0, "impulse": [0, "1", 0]})"), 400,
               "impulse");
  expect_error(
      http_post(port_, "/api/impulse", R"({"body": 0, "impulse": [0, 1, 0], "point": [1e400, 0, 0]})"),
      400, "");
  expect_error(http_post(port_, "/api/impulse", R"({"body": true, "impulse": [0, 1, 0]})"), 400,
               "body");
  expect_error(http_post(port_, "/api/impulse", R"({"impulse": [0, 1, 0]})"), 400, "body");
  expect_error(http_post(port_, "/api/impulse", R"({"body": 0})"), 400, "impulse");
}

TEST_F(RestApi, Integrator) {
  const HttpReply r = http_post(port_, "/api/integrator", R"({"integrator": "rk4"})");
  EXPECT_EQ(r.json(), (json{{"ok", true}, {"integrator", "rk4"}}));
  EXPECT_EQ(state()["integrator"], "rk4");
  EXPECT_EQ(http_get(port_, "/api/scene").json()["integrator"], "rk4");
  expect_error(http_post(port_, "/api/integrator", R"({"integrator": "verlet"})"), 400,
               "integrator");
  expect_error(http_post(port_, "/api/integrator", R"({"integrator": 3})"), 400, "integrator");
  EXPECT_EQ(state()["integrator"], "rk4");
}

TEST_F(RestApi, ResetRestartsAndSwitchesScenes) {
  std::this_thread::sleep_for(150ms);
  EXPECT_GT(state()["time"].get<double>(), 0.05);
  HttpReply r = http_post(port_, "/api/reset");
  ASSERT_EQ(r.status, 200u) << r.body;
  EXPECT_EQ(r.json(), (json{{"ok", true}, {"scene", "seed"}}));
  EXPECT_LT(state()["time"].get<double>(), 0.1);
  r = http_post(port_, "/api/reset", R"({"scene": "bounce"})");
  ASSERT_EQ(r.status, 200u) << r.body;
  EXPECT_EQ(r.json()["scene"], "bounce");
  EXPECT_EQ(http_get(port_, "/api/scene").json()["name"], "bounce");
  json custom = load_scene("seed").bodies.empty() ? json() : scene_to_json(load_scene("seed"));
  custom["name"] = "custom";
  r = http_post(port_, "/api/reset", json{{"scene", custom}}.dump());
  ASSERT_EQ(r.status, 200u) << r.body;
  EXPECT_EQ(r.json()["scene"], "custom");
}

TEST_F(RestApi, BadResetLeavesTheSimulationRunning) {
  std::this_thread::sleep_for(100ms);
  const double t0 = state()["time"];
  json bad = scene_to_json(load_scene("seed"));
  bad["name"] = "bad";
  bad["bodies"][0]["mass"] = -1;
  expect_error(http_post(port_, "/api/reset", json{{"scene", bad}}.dump()), 400,
               "scene.bodies[0].mass");
  bad["bodies"][0]["mass"] = 1;
  bad["bodies"][0]["colour"] = "#fff";
  expect_error(http_post(port_, "/api/reset", json{{"scene", bad}}.dump()), 400,
               "scene.bodies[0].colour");
  expect_error(http_post(port_, "/api/reset", R"({"scene": "no-such-scene"})"), 404, "scene");
  expect_error(http_post(port_, "/api/reset", R"({"scene": "../scenes/seed"})"), 404, "scene");
  expect_error(http_post(port_, "/api/reset", R"({"scene": 5})"), 400, "scene");
  expect_error(http_post(port_, "/api/reset", R"({"scene": {"bodies": 1}})"), 400,
               "scene.bodies");
  expect_error(http_post(port_, "/api/reset", "{not json"), 400, "");
  std::this_thread::sleep_for(100ms);
  const json s = state();
  EXPECT_GT(s["time"].get<double>(), t0);  // Not restarted, still running.
  EXPECT_FALSE(s["paused"].get<bool>());
  EXPECT_EQ(http_get(port_, "/api/scene").json()["name"], "seed");
}

TEST_F(RestApi, UnknownRouteAndWrongMethod) {
  expect_error(http_get(port_, "/api/nope"), 404, "");
  expect_error(http_post(port_, "/api/nope"), 404, "");
  HttpReply r = http_get(port_, "/api/pause");
  expect_error(r, 405, "");
  EXPECT_EQ(r.headers[boost::beast::http::field::allow], "POST");
  r = http_post(port_, "/api/state");
  expect_error(r, 405, "");
  EXPECT_EQ(r.headers[boost::beast::http::field::allow], "GET, HEAD");
  r = http_request(port_, boost::beast::http::verb::delete_, "/api/reset");
  EXPECT_EQ(r.status, 405u);
}

TEST_F(RestApi, Metrics) {
  const HttpReply r = http_get(port_, "/metrics");
  EXPECT_EQ(r.status, 200u);
  EXPECT_NE(r.headers[boost::beast::http::field::content_type].find("text/plain"),
            std::string::npos);
  for (const char* name :
       {"tumble_step_seconds_bucket{le=\"+Inf\"}", "tumble_step_seconds_count",
        "tumble_real_time_factor", "tumble_bodies_awake", "tumble_bodies_frozen",
        "tumble_viewers", "tumble_frames_sent_total", "tumble_frames_dropped_total",
        "tumble_frame_ticks_skipped_total"})
    EXPECT_NE(r.body.find(name), std::string::npos) << name;
}

TEST_F(RestApi, CrossOriginPostsAreRefused) {
  expect_error(http_post(port_, "/api/pause", "", {{"Origin", "http://evil.example"}}), 403,
               "Origin");
  EXPECT_FALSE(state()["paused"].get<bool>());
  const std::string own = "http://127.0.0.1:" + std::to_string(port_);
  EXPECT_EQ(http_post(port_, "/api/pause", "", {{"Origin", own}}).status, 200u);
  EXPECT_EQ(http_get(port_, "/api/state").status, 200u);  // Reads are not restricted.
}

class RestApiWithToken : public ServerTest {
  void configure(ServerOptions& o) override {
    o.token = "s3cret";
    o.allowed_origin = "http://viewer.example";
  }
};

TEST_F(RestApiWithToken, MutatingEndpointsNeedTheToken) {
  HttpReply r = http_post(port_, "/api/pause");
  expect_error(r, 401, "Authorization");
  EXPECT_NE(r.headers[boost::beast::http::field::www_authenticate].find("Bearer"),
            std::string::npos);
  expect_error(http_post(port_, "/api/pause", "", {{"Authorization", "Bearer wrong!"}}), 401,
               "Authorization");
  expect_error(http_post(port_, "/api/pause", "", {{"Authorization", "Bearer s3cre"}}), 401,
               "Authorization");
  expect_error(http_post(port_, "/api/pause", "", {{"Authorization", "Basic s3cret"}}), 401,
               "Authorization");
  EXPECT_FALSE(state()["paused"].get<bool>());
  r = http_post(port_, "/api/pause", "", {{"Authorization", "Bearer s3cret"}});
  EXPECT_EQ(r.status, 200u) << r.body;
  EXPECT_TRUE(state()["paused"].get<bool>());
  EXPECT_EQ(http_get(port_, "/api/health").status, 200u);  // GETs need no token.
}

TEST_F(RestApiWithToken, AllowedOriginGetsCorsHeaders) {
  HttpReply r = http_request(port_, boost::beast::http::verb::options, "/api/pause", "",
                             {{"Origin", "http://viewer.example"}});
  EXPECT_EQ(r.status, 204u);
  EXPECT_EQ(r.headers[boost::beast::http::field::access_control_allow_origin],
            "http://viewer.example");
  r = http_post(port_, "/api/pause", "",
                {{"Authorization", "Bearer s3cret"}, {"Origin", "http://viewer.example"}});
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.headers[boost::beast::http::field::access_control_allow_origin],
            "http://viewer.example");
  r = http_post(port_, "/api/pause", "",
                {{"Authorization", "Bearer s3cret"}, {"Origin", "http://other.example"}});
  EXPECT_EQ(r.status, 403u);
}

}  // namespace
}  // namespace tumble::server::test
