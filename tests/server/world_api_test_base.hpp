#pragma once
/// A ServerTest that talks to one world's routes: /api/… for "default", /api/worlds/{id}/…
/// for the others, with the world's write token on POSTs once it is known (tokens_).
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "server_fixture.hpp"

namespace tumble::server::test {

class WorldApiTest : public ServerTest {
 protected:
  /// The route prefix of `world`.
  static std::string prefix(const std::string& world) {
    return world == "default" ? "/api" : "/api/worlds/" + world;
  }
  /// POSTs `body` to the world's `route` (with its token when one is known).
  HttpReply post(const std::string& world, const std::string& route, const std::string& body = {}) {
    std::map<std::string, std::string> headers;
    if (tokens_.count(world)) headers["Authorization"] = "Bearer " + tokens_[world];
    return http_post(port_, prefix(world) + "/" + route, body, headers);
  }
  /// The same, expecting 200; its JSON.
  nlohmann::json ok(const std::string& world, const std::string& route,
                    const std::string& body = {}) {
    const HttpReply r = post(world, route, body);
    EXPECT_EQ(r.status, 200u) << route << ' ' << body << ": " << r.body;
    return r.json();
  }
  /// GETs the world's `route`, expecting 200; its JSON.
  nlohmann::json get(const std::string& world, const std::string& route) {
    const HttpReply r = http_get(port_, prefix(world) + "/" + route);
    EXPECT_EQ(r.status, 200u) << route << ": " << r.body;
    return r.json();
  }

  std::map<std::string, std::string> tokens_;  ///< Write token of each world created.
};

}  // namespace tumble::server::test
