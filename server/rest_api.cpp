#include "rest_api.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "request_limits.hpp"
#include "tumble/scene_io.hpp"

namespace tumble::server {

namespace http = boost::beast::http;
using nlohmann::json;

namespace {

/// A request refused at the boundary (thrown by the parsers below, caught in handle_api).
struct Refusal {
  unsigned status;
  std::string message;
  std::string field;
};

using Handler = void (*)(const Request&, ServerContext&, const Reply&);

struct Route {
  std::string_view path;
  http::verb method;
  Handler handler;
};

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

/// Largest impulse component accepted, N·s, and largest point coordinate, m (the scene's
/// own position bound).
constexpr double kMaxImpulse = 1e6;
constexpr double kMaxPoint = 1e6;

// ---- Commands ------------------------------------------------------------------------

void submit(ServerContext& ctx, const Request& req, CommandKind kind, const Reply& reply) {
  const unsigned version = req.version();
  const bool keep_alive = req.keep_alive();
  ctx.sim.submit({std::move(kind), [reply, version, keep_alive](CommandResult r) {
                    reply(json_response(version, keep_alive, r.status, r.body));
                  }});
}

Scene scene_from_request(const json& scene) {
  const auto prefixed = [](const std::string& field) {
    return field.empty() ? std::string("scene") : "scene." + field;
  };
  if (scene.is_string()) {
    const std::string name = scene.get<std::string>();
    const std::vector<std::string> names = bundled_scene_names();
    if (std::find(names.begin(), names.end(), name) == names.end())
      throw Refusal{404, "no bundled scene named '" + quoted_prefix(name) + "'", "scene"};
    try {
      return load_scene(name);
    } catch (const SceneParseError& e) {
      throw Refusal{400, e.what(), prefixed(e.field)};
    }
  }
  if (!scene.is_object())
    throw Refusal{400, "expected a bundled scene name or a scene object", "scene"};
  try {
    Scene parsed = scene_from_json(scene);
    if (parsed.world.dt < kMinDt)
      throw Refusal{400, "dt must be at least 1e-6 s", "scene.dt"};
    return parsed;
  } catch (const Refusal&) {
    throw;
  } catch (const SceneParseError& e) {  // Its message and field may quote a client's key.
    throw Refusal{400, quoted_prefix(e.what(), 160), quoted_prefix(prefixed(e.field), 96)};
  } catch (const std::exception& e) {
    throw Refusal{400, e.what(), "scene"};
  }
}

void post_reset(const Request& req, ServerContext& ctx, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"scene"});
  ResetCommand c;
  if (body.contains("scene")) c.scene = scene_from_request(body["scene"]);
  submit(ctx, req, std::move(c), reply);
}

// The protocol says these bodies are empty: anything else is a client that meant something.
void require_empty_body(const Request& req) {
  if (!req.body().empty()) throw Refusal{400, "this request takes no body", ""};
}

void post_pause(const Request& req, ServerContext& ctx, const Reply& reply) {
  require_empty_body(req);
  submit(ctx, req, PauseCommand{}, reply);
}

void post_resume(const Request& req, ServerContext& ctx, const Reply& reply) {
  require_empty_body(req);
  submit(ctx, req, ResumeCommand{}, reply);
}

void post_step(const Request& req, ServerContext& ctx, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"steps"});
  const json& steps = required(body, "steps");
  if (!steps.is_number_integer()) throw Refusal{400, "steps must be an integer", "steps"};
  const bool huge = steps.is_number_unsigned() && steps.get<std::uint64_t>() > 100000;
  const std::int64_t n = huge ? 0 : steps.get<std::int64_t>();
  if (n < 1 || n > 100000) throw Refusal{400, "steps must be in 1..100000", "steps"};
  submit(ctx, req, StepCommand{static_cast<std::uint32_t>(n)}, reply);
}

void post_impulse(const Request& req, ServerContext& ctx, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"body", "impulse", "point"});
  ImpulseCommand c;
  const json& b = required(body, "body");
  if (b.is_string()) {
    c.body = b.get<std::string>();
  } else if (b.is_number_integer()) {
    if (b.is_number_unsigned() ? b.get<std::uint64_t>() > 0xffffffffu : b.get<std::int64_t>() < 0)
      throw Refusal{404, "no body with index " + b.dump(), "body"};
    c.body = static_cast<BodyId>(b.get<std::uint64_t>());
  } else {
    throw Refusal{400, "body must be an index or a name", "body"};
  }
  c.impulse = finite_vec3(required(body, "impulse"), "impulse", kMaxImpulse);
  if (body.contains("point")) c.point = finite_vec3(body["point"], "point", kMaxPoint);
  submit(ctx, req, std::move(c), reply);
}

void post_integrator(const Request& req, ServerContext& ctx, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"integrator"});
  const json& name = required(body, "integrator");
  if (!name.is_string()) throw Refusal{400, "integrator must be a string", "integrator"};
  const std::optional<Integrator> i = parse_integrator(name.get<std::string>());
  if (!i)
    throw Refusal{400, "unknown integrator '" + quoted_prefix(name.get<std::string>()) + "'",
                  "integrator"};
  submit(ctx, req, SetIntegratorCommand{*i}, reply);
}

// ---- Reads from the latest snapshot ----------------------------------------------------

void get_health(const Request& req, ServerContext&, const Reply& reply) {
  reply(ok(req, {{"status", "ok"}}));
}

void get_scene(const Request& req, ServerContext& ctx, const Reply& reply) {
  reply(ok(req, scene_json(*ctx.sim.latest())));
}

void get_scenes(const Request& req, ServerContext&, const Reply& reply) {
  reply(ok(req, {{"scenes", bundled_scene_names()}}));
}

void get_state(const Request& req, ServerContext& ctx, const Reply& reply) {
  reply(ok(req, state_json(*ctx.sim.latest())));
}

void get_metrics(const Request& req, ServerContext& ctx, const Reply& reply) {
  Response res{http::status::ok, req.version()};
  res.set(http::field::content_type, "text/plain; version=0.0.4; charset=utf-8");
  res.keep_alive(req.keep_alive());
  res.body() = ctx.metrics.render(*ctx.sim.latest(), ctx.broadcaster.viewers());
  res.prepare_payload();
  reply(std::move(res));
}

constexpr Route kRoutes[] = {
    {"/api/health", http::verb::get, get_health},
    {"/api/scene", http::verb::get, get_scene},
    {"/api/scenes", http::verb::get, get_scenes},
    {"/api/state", http::verb::get, get_state},
    {"/metrics", http::verb::get, get_metrics},
    {"/api/reset", http::verb::post, post_reset},
    {"/api/pause", http::verb::post, post_pause},
    {"/api/resume", http::verb::post, post_resume},
    {"/api/step", http::verb::post, post_step},
    {"/api/impulse", http::verb::post, post_impulse},
    {"/api/integrator", http::verb::post, post_integrator},
};

// ---- Access checks ---------------------------------------------------------------------

// The Access-Control-Allow-Origin value for this request ("" for none).
std::string cors_origin(const Request& req, const ServerOptions& options) {
  const std::string_view origin = req[http::field::origin];
  if (origin.empty() || options.allowed_origin.empty()) return {};
  if (options.allowed_origin != "*" && origin != options.allowed_origin) return {};
  return std::string(origin);
}

std::string_view path_of(std::string_view target) {
  return target.substr(0, target.find_first_of("?#"));
}

}  // namespace

bool token_matches(std::string_view given, std::string_view expected) {
  unsigned char diff = given.size() == expected.size() ? 0 : 1;
  for (std::size_t i = 0; i < expected.size(); ++i)
    diff |= static_cast<unsigned char>(expected[i] ^ (i < given.size() ? given[i] : 0));
  return diff == 0;
}

bool authorised(const Request& req, const ServerOptions& options) {
  if (options.token.empty()) return true;
  const std::string_view auth = req[http::field::authorization];
  constexpr std::string_view kScheme = "bearer ";
  if (auth.size() < kScheme.size()) return token_matches({}, options.token);
  std::string scheme(auth.substr(0, kScheme.size()));
  std::transform(scheme.begin(), scheme.end(), scheme.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return scheme == kScheme && token_matches(auth.substr(kScheme.size()), options.token);
}

bool is_api_target(std::string_view target) {
  const std::string_view path = path_of(target);
  return path == "/api" || path.starts_with("/api/") || path == "/metrics";
}

bool origin_allowed(const Request& request, const ServerOptions& options) {
  const std::string_view origin = request[http::field::origin];
  if (origin.empty()) return true;
  if (options.allowed_origin == "*" || (!options.allowed_origin.empty() &&
                                        origin == options.allowed_origin))
    return true;
  const std::string_view host = request[http::field::host];
  return !host.empty() && (origin == "http://" + std::string(host) ||
                           origin == "https://" + std::string(host));
}

Response error_response(const Request& req, unsigned status, std::string_view message,
                        std::string_view field) {
  return json_response(req.version(), req.keep_alive(), status,
                       {{"error", message}, {"field", field}});
}

void handle_api(const Request& req, ServerContext& ctx, Reply reply) {
  const ServerOptions& options = ctx.options;
  // Every response passes through here so that CORS headers are added in one place; it
  // may run after `req` is gone (on the simulation thread), so it copies what it needs.
  Reply answer = [cors = cors_origin(req, options), reply = std::move(reply)](Response res) {
    if (!cors.empty()) {
      res.set(http::field::access_control_allow_origin, cors);
      res.set(http::field::vary, "Origin");
    }
    reply(std::move(res));
  };
  const std::string_view path = path_of(req.target());
  std::string allow;
  const Route* route = nullptr;
  for (const Route& r : kRoutes) {
    if (r.path != path) continue;
    allow = r.method == http::verb::get ? "GET, HEAD" : "POST";
    if (r.method == req.method() || (r.method == http::verb::get && req.method() == http::verb::head))
      route = &r;
  }
  try {
    if (allow.empty()) throw Refusal{404, "no such route: " + quoted_prefix(path), ""};
    if (req.method() == http::verb::options && !options.allowed_origin.empty()) {
      Response res{http::status::no_content, req.version()};
      res.set(http::field::allow, allow);
      res.set(http::field::access_control_allow_methods, allow);
      res.set(http::field::access_control_allow_headers, "Content-Type, Authorization");
      res.set(http::field::access_control_max_age, "600");
      res.keep_alive(req.keep_alive());
      res.prepare_payload();
      return answer(std::move(res));
    }
    if (!route) {
      Response res = error_response(req, 405, "method not allowed", "");
      res.set(http::field::allow, allow);
      return answer(std::move(res));
    }
    const bool guarded = route->method == http::verb::post ||
                         (options.token_reads && route->path != "/api/health");
    if (guarded) {
      if (!authorised(req, options)) {
        Response res = error_response(req, 401, "missing or wrong bearer token", "Authorization");
        res.set(http::field::www_authenticate, "Bearer realm=\"tumble\"");
        return answer(std::move(res));
      }
    }
    if (route->method == http::verb::post && !origin_allowed(req, options))
      throw Refusal{403, "requests from this origin are not allowed", "Origin"};
    route->handler(req, ctx, answer);
  } catch (const Refusal& r) {
    answer(error_response(req, r.status, r.message, r.field));
  } catch (const std::exception& e) {
    answer(error_response(req, 500, e.what(), ""));
  }
}

}  // namespace tumble::server
