#include "rest_routes.hpp"

#include <algorithm>
#include <cmath>

#include "request_limits.hpp"
#include "sim_loop.hpp"
#include "worlds.hpp"

namespace tumble::server::rest {

namespace http = boost::beast::http;
using nlohmann::json;

Response json_response(unsigned version, bool keep_alive, unsigned status, const json& body) {
  Response res{static_cast<http::status>(status), version};
  res.set(http::field::content_type, "application/json");
  res.set(http::field::cache_control, "no-store");
  res.keep_alive(keep_alive);
  res.body() = body.dump(-1, ' ', false, json::error_handler_t::replace);
  res.prepare_payload();
  return res;
}

Response ok(const Request& req, const json& body) {
  return json_response(req.version(), req.keep_alive(), 200, body);
}

// ---- Parsing at the boundary ---------------------------------------------------------

json parse_body(const Request& req) {
  const std::string& body = req.body();
  // A raw NUL is never valid JSON, but nlohmann's lexer takes it for the end of the input:
  // "{}\0garbage" would pass.
  if (body.find('\0') != std::string::npos)
    throw Refusal{400, "malformed JSON: NUL byte in the body", ""};
  if (json_too_deep(body))
    throw Refusal{400, "JSON nested deeper than " + std::to_string(kJsonDepthLimit), ""};
  if (std::all_of(body.begin(), body.end(), [](unsigned char c) { return std::isspace(c); }))
    return json::object();
  json j;
  try {
    j = json::parse(body);
  } catch (const json::parse_error& e) {
    throw Refusal{400, std::string("malformed JSON: ") + e.what(), ""};
  } catch (const json::exception& e) {  // e.g. 1e999: a number that is not finite as a double
    throw Refusal{400, std::string("invalid JSON number: ") + e.what(), ""};
  }
  if (!j.is_object()) throw Refusal{400, "the request body must be a JSON object", ""};
  return j;
}

void only_keys(const json& j, std::initializer_list<std::string_view> keys) {
  for (const auto& [key, value] : j.items())
    if (std::find(keys.begin(), keys.end(), key) == keys.end())
      throw Refusal{400, "unknown field '" + quoted_prefix(key) + "'", quoted_prefix(key)};
}

const json& required(const json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end()) throw Refusal{400, std::string("missing field '") + key + "'", key};
  return *it;
}

// Three finite numbers, each within ±limit (finite but huge values such as 1e308 would
// only make the body go non-finite a step later).
Vec3 finite_vec3(const json& j, const char* field, double limit) {
  if (!j.is_array() || j.size() != 3)
    throw Refusal{400, "expected an array of 3 numbers", field};
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    if (!j[i].is_number()) throw Refusal{400, "expected an array of 3 numbers", field};
    v[i] = j[i].get<double>();
    if (!std::isfinite(v[i])) throw Refusal{400, "numbers must be finite", field};
    if (std::abs(v[i]) > limit)
      throw Refusal{400, "each component must be within ±" + json(limit).dump(), field};
  }
  return v;
}


// ---- Commands ------------------------------------------------------------------------

// The outcome becomes HTTP here, on whichever thread completes it (cheap: one JSON dump).
void submit(HostedWorld& world, const Request& req, CommandKind kind, const Reply& reply) {
  const unsigned version = req.version();
  const bool keep_alive = req.keep_alive();
  world.sim().submit({std::move(kind), [reply, version, keep_alive](CommandOutcome r) {
                        reply(json_response(version, keep_alive, outcome_status(r),
                                            outcome_json(r)));
                      }});
}

}  // namespace tumble::server::rest
