// The bad-input catalogue of docs/hardening.md, table-driven against a real in-process server.
// Every case checks: the status, the JSON error naming the field (when the answer is HTTP),
// that the server is alive afterwards, and that /api/state is unchanged except for the
// simulation advancing (same scene, same bodies, not paused, not restarted).
#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/write.hpp>

#include <functional>

#include "frame.hpp"
#include "server_fixture.hpp"

namespace tumble::server::test {
namespace {

using nlohmann::json;
using namespace std::chrono_literals;
namespace http = boost::beast::http;
namespace net = boost::asio;
using tcp = net::ip::tcp;

/// The running scene as JSON, to be broken in one place.
json seed() { return scene_to_json(load_scene("seed")); }

/// {"scene": seed with `edit` applied} as a request body.
std::string reset_with(const std::function<void(json&)>& edit) {
  json s = seed();
  edit(s);
  return json{{"scene", s}}.dump();
}

/// Writes `raw` on a fresh connection, then closes it without reading (abrupt client).
void write_and_vanish(std::uint16_t port, const std::string& raw,
                      std::chrono::milliseconds hold = 0ms) {
  net::io_context ioc;
  tcp::socket s(ioc);
  s.connect({net::ip::make_address("127.0.0.1"), port});
  boost::system::error_code ec;
  net::write(s, net::buffer(raw), ec);
  std::this_thread::sleep_for(hold);
  s.set_option(net::socket_base::linger(true, 0), ec);  // RST, not FIN
  s.close(ec);
}

/// A hand-made masked client WebSocket frame (RFC 6455 §5.2) with payload `data`.
std::string ws_frame(std::uint8_t opcode, const std::string& data, bool truncate = false) {
  std::string f;
  f += static_cast<char>(0x80 | opcode);
  if (data.size() < 126) {
    f += static_cast<char>(0x80 | data.size());
  } else {
    f += static_cast<char>(0x80 | 126);
    f += static_cast<char>(data.size() >> 8);
    f += static_cast<char>(data.size() & 0xff);
  }
  const char mask[4] = {0x11, 0x22, 0x33, 0x44};
  f.append(mask, 4);
  for (std::size_t i = 0; i < data.size(); ++i) f += static_cast<char>(data[i] ^ mask[i % 4]);
  if (truncate) f.resize(f.size() / 2);
  return f;
}

/// The upgrade request for /ws.
std::string ws_upgrade(std::uint16_t port) {
  return "GET /ws HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
         "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
         "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
}

/// A WebSocket connection made by hand: upgrade, read the 101, then write `frames`, and
/// vanish (RST) — garbage, oversized or truncated frames from a misbehaving client.
HttpReply ws_misbehave(std::uint16_t port, const std::string& frames) {
  net::io_context ioc;
  tcp::socket s(ioc);
  s.connect({net::ip::make_address("127.0.0.1"), port});
  net::write(s, net::buffer(ws_upgrade(port)));
  boost::beast::flat_buffer buffer;
  http::response_parser<http::empty_body> parser;
  http::read_header(s, buffer, parser);
  boost::system::error_code ec;
  net::write(s, net::buffer(frames), ec);
  std::this_thread::sleep_for(50ms);
  s.set_option(net::socket_base::linger(true, 0), ec);
  s.close(ec);
  HttpReply r;
  r.status = 101;
  return r;
}

struct Case {
  const char* name;      ///< Test name (and the row in docs/hardening.md).
  std::function<HttpReply(std::uint16_t port)> request;
  unsigned status;       ///< Expected HTTP status (101: a WebSocket case, no JSON body).
  const char* field;     ///< Expected "field" of the JSON error; nullptr: no JSON body.
  const char* allow = nullptr;  ///< Expected Allow header (405).
  std::size_t max_body = 0;     ///< When set: the answer's body is at most this long.
};

HttpReply post(std::uint16_t port, const char* target, std::string body,
               std::map<std::string, std::string> headers = {}) {
  return http_post(port, target, std::move(body), headers);
}

#define POST(target, body) [](std::uint16_t p) { return post(p, target, body); }
#define RESET(...) [](std::uint16_t p) { return post(p, "/api/reset", reset_with(__VA_ARGS__)); }
#define RAW(text) [](std::uint16_t p) { return raw_request(p, text); }
#define GET(target) [](std::uint16_t p) { return http_get(p, target); }
#define WS_WITH_KEY(key)                                                                  \
  "GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"     \
  "Sec-WebSocket-Key: " key "\r\nSec-WebSocket-Version: 13\r\n\r\n"
#define HIDDEN_PAUSE "POST /api/pause HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n"
#define SMUGGLE(coding)                                                                  \
  "POST /api/step HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: " coding "\r\n\r\n" HIDDEN_PAUSE

const std::vector<Case>& cases() {
  static const std::vector<Case> table = {
      // ---- Malformed JSON and wrong types ----------------------------------------------
      {"MalformedJson", POST("/api/impulse", "{\"body\": 0,"), 400, ""},
      {"JsonNotAnObject", POST("/api/step", "[1, 2]"), 400, ""},
      {"JsonBareString", POST("/api/reset", "\"seed\""), 400, ""},
      {"InvalidUtf8", POST("/api/reset", "{\"scene\": \"\xff\xfe\"}"), 400, ""},
      {"TrailingNul", POST("/api/step", std::string("{\"steps\": 1}\0", 13)), 400, ""},
      {"MillionBrackets", POST("/api/step", std::string(1000000, '[')), 400, ""},
      {"JsonDepth33",
       POST("/api/step", R"({"steps": [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]})"),
       400, ""},
      {"PauseWithBody", POST("/api/pause", "{}"), 400, ""},
      {"ResumeWithBody", POST("/api/resume", "x"), 400, ""},
      {"HugeUnknownKeyNotEchoed",
       [](std::uint16_t p) {
         return post(p, "/api/step", "{\"steps\": 1, \"" + std::string(900000, 'k') + "\": 1}");
       },
       400, "kkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkkk…", nullptr, 400},
      {"HugeUnknownSceneKeyNotEchoed",
       [](std::uint16_t p) {
         return post(p, "/api/reset", reset_with([](json& s) { s[std::string(900000, 'k')] = 1; }));
       },
       400, nullptr, nullptr, 600},
      {"StepsWrongType", POST("/api/step", R"({"steps": "3"})"), 400, "steps"},
      {"BodyWrongType", POST("/api/impulse", R"({"body": [0], "impulse": [0, 1, 0]})"), 400,
       "body"},
      {"ImpulseWrongType", POST("/api/impulse", R"({"body": 0, "impulse": "up"})"), 400,
       "impulse"},
      {"ImpulseTwoNumbers", POST("/api/impulse", R"({"body": 0, "impulse": [0, 1]})"), 400,
       "impulse"},
      {"PointWrongType", POST("/api/impulse", R"({"body": 0, "impulse": [0, 1, 0], "point": {}})"),
       400, "point"},
      {"IntegratorWrongType", POST("/api/integrator", R"({"integrator": null})"), 400,
       "integrator"},
      {"SceneWrongType", POST("/api/reset", R"({"scene": 5})"), 400, "scene"},
      // ---- Missing and extra fields ------------------------------------------------------
      {"StepsMissing", POST("/api/step", "{}"), 400, "steps"},
      {"BodyMissing", POST("/api/impulse", R"({"impulse": [0, 1, 0]})"), 400, "body"},
      {"ImpulseMissing", POST("/api/impulse", R"({"body": 0})"), 400, "impulse"},
      {"IntegratorMissing", POST("/api/integrator", "{}"), 400, "integrator"},
      {"ExtraFieldStep", POST("/api/step", R"({"steps": 1, "force": true})"), 400, "force"},
      {"ExtraFieldReset", POST("/api/reset", R"({"scene": "seed", "x": 1})"), 400, "x"},
      {"ExtraFieldInScene", RESET([](json& s) { s["bodies"][0]["spin"] = 1; }), 400,
       "scene.bodies[0].spin"},
      // ---- NaN, ±Inf, 1e308, −0 in numeric fields -------------------------------------
      {"NaNLiteral", POST("/api/impulse", R"({"body": 0, "impulse": [NaN, 0, 0]})"), 400, ""},
      {"InfinityLiteral", POST("/api/impulse", R"({"body": 0, "impulse": [Infinity, 0, 0]})"),
       400, ""},
      {"OverflowToInf", POST("/api/impulse", R"({"body": 0, "impulse": [0, -1e999, 0]})"), 400,
       ""},
      {"Impulse1e308", POST("/api/impulse", R"({"body": 0, "impulse": [1e308, 0, 0]})"), 400,
       "impulse"},
      {"Point1e308", POST("/api/impulse", R"({"body": 0, "impulse": [0, 1e-9, 0], "point": [0, 0, -1e308]})"),
       400, "point"},
      {"ImpulseMinusZero", POST("/api/impulse", R"({"body": 0, "impulse": [-0.0, -0, -0.0]})"),
       200, nullptr},
      {"Steps1e308", POST("/api/step", R"({"steps": 1e308})"), 400, "steps"},
      {"ImpulsePastSpeedLimit", POST("/api/impulse", R"({"body": 0, "impulse": [1e6, 0, 0]})"),
       400, "impulse"},
      {"ImpulsePastSpinLimit",
       POST("/api/impulse", R"({"body": 0, "impulse": [0, 0, 100], "point": [0, 1e3, 0]})"), 400,
       "impulse"},
      {"ScenePackedAtOnePoint",  // 2,000 boxes at one point: two million pairs (issue 12, item 2)
       RESET([](json& s) {
         json bodies = json::array();
         for (int i = 0; i < 2000; ++i)
           bodies.push_back({{"name", "b" + std::to_string(i)}, {"position", {0, 5, 0}}});
         s["bodies"] = bodies;
       }),
       400, "scene.bodies"},
      {"SceneDtTiny",
       RESET([](json& s) {
         s["dt"] = 1e-9;  // Valid for the engine (its TOI tolerance below it), but a busy loop.
         s["toi_tolerance"] = 1e-12;
       }),
       400, "scene.dt"},
      {"StepsMinusZero", POST("/api/step", R"({"steps": -0})"), 400, "steps"},
      {"SceneMass1e308", RESET([](json& s) { s["bodies"][0]["mass"] = 1e308; }), 400,
       "scene.bodies[0].mass"},
      {"SceneMassMinusZero", RESET([](json& s) { s["bodies"][0]["mass"] = -0.0; }), 400,
       "scene.bodies[0].mass"},
      {"ScenePosition1e308", RESET([](json& s) { s["bodies"][0]["position"][1] = 1e308; }),
       400, "scene.bodies[0].position"},
      {"SceneVelocity1e308", RESET([](json& s) { s["bodies"][0]["velocity"][0] = -1e308; }),
       400, "scene.bodies[0].velocity"},
      {"SceneSpin1e308", RESET([](json& s) { s["bodies"][0]["angular_velocity"][2] = 1e308; }),
       400, "scene.bodies[0].angular_velocity"},
      {"SceneOrientationZero",
       RESET([](json& s) { s["bodies"][0]["orientation"] = {-0.0, 0, 0, 0}; }), 400,
       "scene.bodies[0].orientation"},
      {"SceneGravity1e308", RESET([](json& s) { s["gravity"][1] = -1e308; }), 400,
       "scene.gravity"},
      {"SceneDtMinusZero", RESET([](json& s) { s["dt"] = -0.0; }), 400, "scene.dt"},
      {"SceneDt1e308", RESET([](json& s) { s["dt"] = 1e308; }), 400, "scene.dt"},
      {"SceneFloorHeight1e308", RESET([](json& s) { s["floor"]["height"] = 1e308; }), 400,
       "scene.floor.height"},
      {"SceneRestitution1e308", RESET([](json& s) { s["floor"]["restitution"] = 1e308; }), 400,
       "scene.floor.restitution"},
      {"SceneFriction1e308", RESET([](json& s) { s["bodies"][0]["friction"] = 1e308; }), 400,
       "scene.bodies[0].friction"},
      // ---- Unknown body, steps out of range --------------------------------------------
      {"UnknownBodyName", POST("/api/impulse", R"({"body": "ghost", "impulse": [0, 1, 0]})"),
       404, "body"},
      {"UnknownBodyIndex", POST("/api/impulse", R"({"body": 7, "impulse": [0, 1, 0]})"), 404,
       "body"},
      {"NegativeBodyIndex", POST("/api/impulse", R"({"body": -1, "impulse": [0, 1, 0]})"), 404,
       "body"},
      {"HugeBodyIndex",
       POST("/api/impulse", R"({"body": 18446744073709551615, "impulse": [0, 1, 0]})"), 404,
       "body"},
      {"NegativeSteps", POST("/api/step", R"({"steps": -5})"), 400, "steps"},
      {"ZeroSteps", POST("/api/step", R"({"steps": 0})"), 400, "steps"},
      {"HugeSteps", POST("/api/step", R"({"steps": 99999999999999999999})"), 400, "steps"},
      {"StepWhileRunning", POST("/api/step", R"({"steps": 5})"), 409, "steps"},
      // ---- Invalid scene on reset: refused whole ---------------------------------------
      {"NegativeMass", RESET([](json& s) { s["bodies"][0]["mass"] = -1; }), 400,
       "scene.bodies[0].mass"},
      {"ZeroSize", RESET([](json& s) { s["bodies"][0]["size"] = {1, 0, 1}; }), 400,
       "scene.bodies[0].size"},
      {"UnknownIntegrator", RESET([](json& s) { s["integrator"] = "leapfrog"; }), 400,
       "scene.integrator"},
      {"BadColour", RESET([](json& s) { s["bodies"][0]["color"] = "red"; }), 400,
       "scene.bodies[0].color"},
      {"DuplicateBodyName",
       RESET([](json& s) { s["bodies"].push_back(s["bodies"][0]); }), 400,
       "scene.bodies[1].name"},
      {"SecondBodyBad",
       RESET([](json& s) {
         json b = s["bodies"][0];
         b["name"] = "b2";
         b["size"] = {1, 1, -1};
         s["bodies"].push_back(b);
       }),
       400, "scene.bodies[1].size"},
      {"TooManyBodies",
       [](std::uint16_t p) {
         json s = seed();
         s["bodies"] = json::array();
         for (int i = 0; i < 100001; ++i) s["bodies"].push_back(json::object());
         return post(p, "/api/reset", json{{"scene", s}}.dump());
       },
       400, "scene.bodies"},
      {"MillionBodies",
       [](std::uint16_t p) {
         std::string body = R"({"scene": {"bodies": [)";
         for (int i = 0; i < 1000000; ++i) body += i ? ",{}" : "{}";
         return post(p, "/api/reset", body + "]}}");
       },
       413, ""},
      {"UnknownSceneName", POST("/api/reset", R"({"scene": "nope"})"), 404, "scene"},
      {"ScenePathNotName", POST("/api/reset", R"({"scene": "/etc/passwd"})"), 404, "scene"},
      {"UnknownIntegratorCommand", POST("/api/integrator", R"({"integrator": "verlet"})"), 400,
       "integrator"},
      // ---- HTTP limits, routes and methods ---------------------------------------------
      {"BodyOverLimit",
       [](std::uint16_t p) { return post(p, "/api/reset", std::string(2 << 20, ' ')); }, 413,
       ""},
      {"HugeHeaderLine",
       [](std::uint16_t p) {
         return http_request(p, http::verb::get, "/api/health", {},
                             {{"X-Big", std::string(20000, 'a')}});
       },
       431, ""},
      {"TooManyHeaders",
       [](std::uint16_t p) {
         std::string raw = "GET /api/health HTTP/1.1\r\nHost: x\r\n";
         for (int i = 0; i < 2000; ++i) raw += "X-H" + std::to_string(i) + ": v\r\n";
         return raw_request(p, raw + "\r\n");
       },
       431, ""},
      {"GarbageRequestLine", RAW("\x01\x02 garbage\r\n\r\n"), 400, ""},
      {"BadContentLength", RAW("POST /api/pause HTTP/1.1\r\nContent-Length: -4\r\n\r\n"), 400,
       ""},
      {"Http11WithoutHost", RAW("GET /api/health HTTP/1.1\r\n\r\n"), 400, "Host"},
      {"TwoHosts", RAW("GET /api/health HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n"), 400, "Host"},
      {"ExpectUnknown",
       RAW("POST /api/step HTTP/1.1\r\nHost: x\r\nExpect: teapot\r\nContent-Length: 2\r\n\r\n{}"),
       417, "Expect"},
      // ---- Request framing: a body must never run as a second request (RFC 9112 §6.3) ----
      // Each hides a POST /api/pause in the body; the checks after the row find the
      // simulation still running, so the hidden request never ran.
      {"TransferEncodingXchunked", RAW(SMUGGLE("xchunked")), 400, "Transfer-Encoding"},
      {"TransferEncodingIdentity", RAW(SMUGGLE("identity")), 400, "Transfer-Encoding"},
      {"TransferEncodingGzip", RAW(SMUGGLE("gzip")), 400, "Transfer-Encoding"},
      {"TransferEncodingChunkedIdentity", RAW(SMUGGLE("chunked, identity")), 400,
       "Transfer-Encoding"},
      {"TransferEncodingGzipChunked", RAW(SMUGGLE("gzip, chunked")), 501, "Transfer-Encoding"},
      {"TransferEncodingTwice",
       RAW("POST /api/step HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n"
           "Transfer-Encoding: chunked\r\n\r\n0\r\n\r\n"),
       400, ""},
      {"ContentLengthAndTransferEncoding",
       RAW("POST /api/step HTTP/1.1\r\nHost: x\r\nContent-Length: 5\r\n"
           "Transfer-Encoding: chunked\r\n\r\n0\r\n\r\n" HIDDEN_PAUSE),
       400, ""},
      {"ChunkExtensionTooLong",
       [](std::uint16_t p) {
         return raw_request(p, "POST /api/step HTTP/1.1\r\nHost: x\r\n"
                               "Transfer-Encoding: chunked\r\n\r\nc;" +
                                   std::string(300, 'e') + "\r\n{\"steps\": 1}\r\n0\r\n\r\n");
       },
       400, ""},
      {"ChunkHeaderOverReadBuffer",
       [](std::uint16_t p) {
         return raw_request(p, "POST /api/step HTTP/1.1\r\nHost: x\r\n"
                               "Transfer-Encoding: chunked\r\n\r\n1;" +
                                   std::string(100000, 'e'));
       },
       400, ""},
      {"TrailerOverReadBuffer",
       [](std::uint16_t p) {
         std::string raw = "POST /api/step HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n"
                           "2\r\n{}\r\n0\r\n";
         for (int i = 0; i < 5000; ++i) raw += "X-T" + std::to_string(i) + ": vvvvvvvvvv\r\n";
         return raw_request(p, raw);
       },
       400, ""},
      // A trailer field reached the handler as if sent in the header (RFC 9110 §6.5.1): each
      // hides a pause behind a trailer, so the checks after the row find it never ran.
      {"TrailerField",
       RAW("POST /api/pause HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n"
           "2\r\n{}\r\n0\r\nX-Checksum: 1234\r\n\r\n"),
       400, "X-Checksum"},
      {"TrailerRepeatsHost",
       RAW("POST /api/pause HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n"
           "0\r\nHost: y\r\n\r\n"),
       400, "Host"},
      // ---- Routes and methods ----------------------------------------------------------
      {"UnknownRoute", GET("/api/nothing"), 404, ""},
      {"UnknownRoutePost", POST("/api/explode", "{}"), 404, ""},
      {"WrongMethodGetOnPost", GET("/api/reset"), 405, "", "POST"},
      {"WrongMethodPostOnGet", POST("/api/state", ""), 405, "", "GET, HEAD"},
      {"WrongMethodDelete",
       [](std::uint16_t p) { return http_request(p, http::verb::delete_, "/api/state"); }, 405,
       "", "GET, HEAD"},
      {"WrongMethodStatic", POST("/index.html", ""), 405, "", "GET, HEAD"},
      // ---- Static files: traversal, symlinks, listing ----------------------------------
      {"DotDotTraversal", RAW("GET /../secret.txt HTTP/1.1\r\nHost: x\r\n\r\n"), 403, ""},
      {"EncodedTraversal", GET("/%2e%2e/secret.txt"), 403, ""},
      {"EncodedSlashTraversal", GET("/src/..%2f..%2fsecret.txt"), 403, ""},
      {"AbsolutePath", RAW("GET //etc/passwd HTTP/1.1\r\nHost: x\r\n\r\n"), 403, ""},
      {"AbsoluteFormTarget", RAW("GET /etc/passwd HTTP/1.1\r\nHost: x\r\n\r\n"), 404, ""},
      {"SymlinkOut", GET("/leak.txt"), 403, ""},
      {"SymlinkDirOut", GET("/up/secret.txt"), 403, ""},
      {"NulInPath", GET("/index.html%00.js"), 403, ""},
      {"BadPercentEscape", GET("/%zz"), 400, ""},
      {"NoDirectoryListing", GET("/empty/"), 404, ""},
      {"NodeModulesNotServed", GET("/node_modules/pkg/index.js"), 403, ""},
      {"NodeModulesToolingNotServed", GET("/node_modules/playwright-core/package.json"), 403, ""},
      {"NodeModulesListingNotServed", GET("/node_modules/"), 403, ""},
      {"DotfileNotServed", GET("/.env"), 403, ""},
      // ---- WebSocket ---------------------------------------------------------------------
      {"WsWrongOrigin",
       [](std::uint16_t p) {
         HttpReply r = raw_request(
             p, "GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nOrigin: http://evil.example\r\n"
                "Upgrade: websocket\r\nConnection: Upgrade\r\n"
                "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n");
         return r;
       },
       403, "Origin"},
      {"WsWithoutUpgrade", GET("/ws"), 426, ""},
      {"WsKeyEmpty", RAW(WS_WITH_KEY("")), 400, "Sec-WebSocket-Key"},
      {"WsKeyShort", RAW(WS_WITH_KEY("c2hvcnQ=")), 400, "Sec-WebSocket-Key"},
      {"WsKeyNotBase64", RAW(WS_WITH_KEY("!!!!!!!!!!!!!!!!!!!!!!==")), 400, "Sec-WebSocket-Key"},
      {"WsKeySeventeenBytes", RAW(WS_WITH_KEY("AAAAAAAAAAAAAAAAAAAAAAA=")), 400,
       "Sec-WebSocket-Key"},
      {"WsTextGarbage",
       [](std::uint16_t p) { return ws_misbehave(p, ws_frame(0x1, "{\"type\": \"take over\"")); },
       101, nullptr},
      {"WsBinaryGarbage",
       [](std::uint16_t p) { return ws_misbehave(p, ws_frame(0x2, std::string(300, '\xee'))); },
       101, nullptr},
      {"WsInvalidOpcode",
       [](std::uint16_t p) { return ws_misbehave(p, ws_frame(0x7, "???")); }, 101, nullptr},
      {"WsUnmaskedGarbageBytes",
       [](std::uint16_t p) { return ws_misbehave(p, std::string(64, '\xff')); }, 101, nullptr},
      {"WsOversizedMessage",
       [](std::uint16_t p) { return ws_misbehave(p, ws_frame(0x2, std::string(60000, 'x'))); },
       101, nullptr},
      {"WsDisconnectMidFrame",
       [](std::uint16_t p) {
         return ws_misbehave(p, ws_frame(0x2, std::string(1000, 'x'), /*truncate=*/true));
       },
       101, nullptr},
      {"WsHandshakeNeverCompleted",
       [](std::uint16_t p) {
         write_and_vanish(p, "GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgr", 300ms);
         HttpReply r;
         r.status = 101;
         return r;
       },
       101, nullptr},
  };
  return table;
}

class BadInput : public ServerTest, public ::testing::WithParamInterface<Case> {};

TEST_P(BadInput, RefusedAndNothingLost) {
  const Case& c = GetParam();
  // A viewer connected throughout: it must keep getting frames whatever the case does.
  WsClient viewer(port_);
  ASSERT_TRUE(viewer.read());  // the scene message
  std::this_thread::sleep_for(40ms);
  const json before = state();
  ASSERT_TRUE(before.is_object());

  const HttpReply r = c.request(port_);
  EXPECT_EQ(r.status, c.status) << r.body << " " << r.error.message();
  if (c.field) {
    const json j = r.json();
    ASSERT_TRUE(j.is_object()) << r.body;
    EXPECT_TRUE(j["error"].is_string()) << r.body;
    EXPECT_EQ(j["field"], c.field) << r.body;
  }
  if (c.allow) {
    EXPECT_EQ(r.headers[http::field::allow], c.allow);
  }
  if (c.max_body) {
    EXPECT_LE(r.body.size(), c.max_body) << r.body.substr(0, 200);
  }

  // Alive, and the same simulation, only further on.
  std::this_thread::sleep_for(60ms);
  EXPECT_EQ(http_get(port_, "/api/health").status, 200u);
  const json after = state();
  ASSERT_TRUE(after.is_object());
  EXPECT_GT(after["time"].get<double>(), before["time"].get<double>());
  EXPECT_GT(after["step"].get<std::int64_t>(), before["step"].get<std::int64_t>());
  EXPECT_FALSE(after["paused"].get<bool>());
  EXPECT_EQ(after["integrator"], before["integrator"]);
  ASSERT_EQ(after["bodies"].size(), before["bodies"].size());
  EXPECT_EQ(after["bodies"][0]["name"], before["bodies"][0]["name"]);
  EXPECT_FALSE(after["bodies"][0]["frozen"].get<bool>());
  EXPECT_EQ(http_get(port_, "/api/scene").json()["name"], "seed");
  int frames = 0;
  for (int i = 0; i < 6 && frames < 2; ++i) {
    const auto m = viewer.read(1s);
    ASSERT_TRUE(m) << "viewer starved: " << viewer.last_error().message();
    if (!m->text && decode_frame(m->data)) ++frames;
  }
  EXPECT_EQ(frames, 2);
}

INSTANTIATE_TEST_SUITE_P(Catalogue, BadInput, ::testing::ValuesIn(cases()),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(BadInputCatalogue, HasAtLeastFortyCases) { EXPECT_GE(cases().size(), 40u); }

// Access: with --token every mutating endpoint needs it; reads stay open.
class BadInputToken : public ServerTest {
  void configure(ServerOptions& o) override { o.token = "t0ken"; }
};

TEST_F(BadInputToken, EveryPostNeedsTheToken) {
  const json before = state();
  for (const char* target : {"/api/reset", "/api/pause", "/api/resume", "/api/step",
                             "/api/impulse", "/api/integrator"}) {
    for (const std::map<std::string, std::string>& h :
         {std::map<std::string, std::string>{},
          {{"Authorization", "Bearer t0ke"}},
          {{"Authorization", "Bearer t0kenX"}},
          {{"Authorization", "bearer"}}}) {
      const HttpReply r = http_post(port_, target, "{}", h);
      EXPECT_EQ(r.status, 401u) << target;
      EXPECT_EQ(r.json()["field"], "Authorization") << target;
    }
  }
  EXPECT_EQ(http_get(port_, "/api/state").status, 200u);
  EXPECT_EQ(http_get(port_, "/metrics").status, 200u);
  std::this_thread::sleep_for(40ms);
  const json after = state();
  EXPECT_GT(after["time"].get<double>(), before["time"].get<double>());
  EXPECT_FALSE(after["paused"].get<bool>());
}

// The token sent as a trailer field is refused, not read as the header's Authorization.
TEST_F(BadInputToken, ATrailerCannotAuthorize) {
  const HttpReply r = raw_request(
      port_, "POST /api/pause HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n"
             "0\r\nAuthorization: Bearer t0ken\r\n\r\n");
  EXPECT_EQ(r.status, 400u) << r.body;
  EXPECT_EQ(r.json()["field"], "Authorization") << r.body;
  std::this_thread::sleep_for(40ms);
  EXPECT_FALSE(state()["paused"].get<bool>());
}

// Viewer cap: the next viewer gets a clear refusal, the others keep their stream.
class BadInputViewerCap : public ServerTest {
  void configure(ServerOptions& o) override { o.max_viewers = 2; }
};

TEST_F(BadInputViewerCap, NextViewerIsRefusedWith503) {
  WsClient a(port_), b(port_);
  ASSERT_TRUE(a.read());
  ASSERT_TRUE(b.read());
  const HttpReply r = raw_request(port_, ws_upgrade(port_));
  EXPECT_EQ(r.status, 503u);
  EXPECT_EQ(r.json()["error"], "too many viewers");
  for (WsClient* c : {&a, &b}) {
    const auto m = c->read(1s);
    ASSERT_TRUE(m);
  }
}

}  // namespace
}  // namespace tumble::server::test
