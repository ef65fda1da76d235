#include "rest_api.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "request_limits.hpp"
#include "rest_routes.hpp"
#include "sim_loop.hpp"
#include "timeline_json.hpp"
#include "tumble/scene_io.hpp"
#include "worlds.hpp"

namespace tumble::server {

namespace http = boost::beast::http;
using nlohmann::json;


using namespace rest;

namespace {

/// A route of one world: "/api/state" … (also under /api/worlds/{id}/…).
using WorldHandler = void (*)(const Request&, ServerContext&, HostedWorld&, const Reply&);
/// A route of the server: health, scenes, metrics, the worlds collection.
using ServerHandler = void (*)(const Request&, ServerContext&, const Reply&);

struct WorldRoute {
  std::string_view path;
  http::verb method;
  WorldHandler handler;
};

struct ServerRoute {
  std::string_view path;
  http::verb method;
  ServerHandler handler;
};

Scene parse_scene(const json& scene) {
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

Scene scene_from_request(const json& scene, const ServerOptions& options) {
  Scene parsed = parse_scene(scene);
  if (parsed.bodies.size() > static_cast<std::size_t>(options.max_bodies))
    throw Refusal{400,
                  "the scene has " + std::to_string(parsed.bodies.size()) +
                      " bodies; this server takes at most " + std::to_string(options.max_bodies) +
                      " per world (--max-bodies)",
                  "scene.bodies"};
  return parsed;
}

void post_reset(const Request& req, ServerContext& ctx, HostedWorld& world, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"scene"});
  ResetCommand c;
  if (body.contains("scene")) c.scene = scene_from_request(body["scene"], ctx.options);
  submit(world, req, std::move(c), reply);
}

// The protocol says these bodies are empty: anything else is a client that meant something.
void require_empty_body(const Request& req) {
  if (!req.body().empty()) throw Refusal{400, "this request takes no body", ""};
}

void post_pause(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  require_empty_body(req);
  submit(world, req, PauseCommand{}, reply);
}

void post_resume(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  require_empty_body(req);
  submit(world, req, ResumeCommand{}, reply);
}

void post_step(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"steps"});
  const json& steps = required(body, "steps");
  if (!steps.is_number_integer()) throw Refusal{400, "steps must be an integer", "steps"};
  const bool huge = steps.is_number_unsigned() && steps.get<std::uint64_t>() > 100000;
  const std::int64_t n = huge ? 0 : steps.get<std::int64_t>();
  if (n < 1 || n > 100000) throw Refusal{400, "steps must be in 1..100000", "steps"};
  submit(world, req, StepCommand{static_cast<std::uint32_t>(n)}, reply);
}

void post_impulse(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
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
  submit(world, req, std::move(c), reply);
}

void post_integrator(const Request& req, ServerContext&, HostedWorld& world,
                     const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"integrator"});
  const json& name = required(body, "integrator");
  if (!name.is_string()) throw Refusal{400, "integrator must be a string", "integrator"};
  const std::optional<Integrator> i = parse_integrator(name.get<std::string>());
  if (!i)
    throw Refusal{400, "unknown integrator '" + quoted_prefix(name.get<std::string>()) + "'",
                  "integrator"};
  submit(world, req, SetIntegratorCommand{*i}, reply);
}

// ---- Reads from the latest snapshot ----------------------------------------------------

void get_health(const Request& req, ServerContext&, const Reply& reply) {
  reply(ok(req, {{"status", "ok"}}));
}

void get_scene(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  reply(ok(req, scene_json(*world.sim().latest())));
}

void get_scenes(const Request& req, ServerContext&, const Reply& reply) {
  reply(ok(req, {{"scenes", bundled_scene_names()}}));
}

void get_state(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  reply(ok(req, state_json(*world.sim().latest())));
}

void get_metrics(const Request& req, ServerContext& ctx, const Reply& reply) {
  std::vector<WorldGauges> gauges;
  for (const auto& world : ctx.worlds.list()) {
    const auto snap = world->sim().latest();
    gauges.push_back({world->id(), snap->real_time_factor, snap->time, snap->bodies->size(),
                      snap->awake, world->broadcaster().viewers(), snap->paused,
                      snap->history_bytes});
  }
  Response res{http::status::ok, req.version()};
  res.set(http::field::content_type, "text/plain; version=0.0.4; charset=utf-8");
  res.keep_alive(req.keep_alive());
  res.body() = ctx.metrics.render(*ctx.worlds.default_world()->sim().latest(),
                                  ctx.worlds.viewers()) +
               render_world_gauges(gauges);
  res.prepare_payload();
  reply(std::move(res));
}

// ---- Worlds ----------------------------------------------------------------------------

json world_json(HostedWorld& world) {
  const auto snap = world.sim().latest();
  return {{"id", world.id()},
          {"scene", snap->scene->scene.world.name},
          {"bodies", snap->bodies->size()},
          {"viewers", world.broadcaster().viewers()},
          {"real_time_factor", snap->real_time_factor},
          {"paused", snap->paused},
          {"time", snap->time}};
}

void get_worlds(const Request& req, ServerContext& ctx, const Reply& reply) {
  json worlds = json::array();
  for (const auto& world : ctx.worlds.list()) worlds.push_back(world_json(*world));
  reply(ok(req, {{"worlds", std::move(worlds)}, {"max_worlds", ctx.worlds.max_worlds()}}));
}

void get_world(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  reply(ok(req, world_json(world)));
}

// The scene a PUT names is its identity: the same name (or the same scene object, whose JSON
// nlohmann keeps with sorted keys) makes the PUT idempotent; anything else is a conflict.
void put_world(const Request& req, ServerContext& ctx, std::string_view id, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"scene"});
  const json& scene = required(body, "scene");
  const std::string key = scene.is_string() ? scene.get<std::string>() : scene.dump();
  CreateResult r = ctx.worlds.create(std::string(id), key, scene_from_request(scene, ctx.options));
  switch (r.refusal) {
    case CreateRefusal::bad_id:
      throw Refusal{400, "a world id is 1 to 64 of a-z, 0-9 and '-'", "id"};
    case CreateRefusal::conflict:
      throw Refusal{409, "world '" + std::string(id) + "' exists with another scene", "scene"};
    case CreateRefusal::too_many:
      throw Refusal{429,
                    "this server holds its most worlds (" +
                        std::to_string(ctx.worlds.max_worlds()) + ", --max-worlds)",
                    ""};
    case CreateRefusal::none:
      break;
  }
  r.world->touch();
  json answer = world_json(*r.world);
  answer.erase("viewers");
  if (r.created) answer["token"] = r.world->token();
  reply(json_response(req.version(), req.keep_alive(), r.created ? 201 : 200, answer));
}

void delete_world(const Request& req, ServerContext& ctx, HostedWorld& world,
                  const Reply& reply) {
  require_empty_body(req);
  if (world.id() == kDefaultWorld) throw Refusal{409, "the default world cannot be deleted", "id"};
  if (!ctx.worlds.remove(world.id()))
    throw Refusal{404, "no world '" + world.id() + "'", "world"};
  reply(ok(req, {{"ok", true}}));
}

/// Routes of one world, unprefixed for the default world and under /api/worlds/{id}.
constexpr WorldRoute kWorldRoutes[] = {
    {"/api/scene", http::verb::get, get_scene},
    {"/api/state", http::verb::get, get_state},
    {"/api/reset", http::verb::post, post_reset},
    {"/api/pause", http::verb::post, post_pause},
    {"/api/resume", http::verb::post, post_resume},
    {"/api/step", http::verb::post, post_step},
    {"/api/impulse", http::verb::post, post_impulse},
    {"/api/integrator", http::verb::post, post_integrator},
    {"/api/history", http::verb::get, get_history},
    {"/api/recording", http::verb::get, get_recording},
    {"/api/seek", http::verb::post, post_seek},
    {"/api/play", http::verb::post, post_play},
    {"/api/speed", http::verb::post, post_speed},
    {"/api/bodies", http::verb::post, post_bodies},
};

/// Routes of the server as a whole.
constexpr ServerRoute kServerRoutes[] = {
    {"/api/health", http::verb::get, get_health},
    {"/api/scenes", http::verb::get, get_scenes},
    {"/api/worlds", http::verb::get, get_worlds},
    {"/metrics", http::verb::get, get_metrics},
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

// What a request path addresses: a route of the server, a route of one world (unprefixed:
// the default world), or a world itself (/api/worlds/{id}).
struct Target {
  enum class Kind { none, server, world_route, world } kind = Kind::none;
  std::string_view id;                    // The world's id (world_route, world).
  const ServerRoute* server = nullptr;    // Kind::server.
  std::string_view route;                 // Kind::world_route: "/state", "/reset", …
};

Target parse_target(std::string_view path) {
  constexpr std::string_view kWorlds = "/api/worlds/";
  if (path.starts_with(kWorlds)) {
    const std::string_view rest = path.substr(kWorlds.size());
    const std::size_t slash = rest.find('/');
    if (slash == std::string_view::npos) return {.kind = Target::Kind::world, .id = rest};
    return {Target::Kind::world_route, rest.substr(0, slash), nullptr, rest.substr(slash)};
  }
  for (const ServerRoute& r : kServerRoutes)
    if (r.path == path) return {.kind = Target::Kind::server, .server = &r};
  if (path.starts_with("/api/"))
    return {Target::Kind::world_route, kDefaultWorld, nullptr, path.substr(4)};
  return {};
}

// The route of world route `route` ("/state") for `method` (null if none), and the methods
// the path allows ("" if the path is no route).
const WorldRoute* find_world_route(std::string_view route, http::verb method,
                                   std::string& allow) {
  for (const WorldRoute& r : kWorldRoutes) {
    if (r.path.substr(4) != route) continue;
    allow = r.method == http::verb::get ? "GET, HEAD" : "POST";
    if (r.method == method || (r.method == http::verb::get && method == http::verb::head))
      return &r;
  }
  return nullptr;
}

Response unauthorised(const Request& req) {
  Response res = error_response(req, 401, "missing or wrong bearer token", "Authorization");
  res.set(http::field::www_authenticate, "Bearer realm=\"tumble\"");
  return res;
}

bool is_get(http::verb method) { return method == http::verb::get || method == http::verb::head; }

// PUT /api/worlds/{id} (needs --token when the server has one), GET and DELETE.
void serve_world(const Request& req, ServerContext& ctx, const Target& t, const Reply& answer) {
  const ServerOptions& options = ctx.options;
  if (req.method() == http::verb::put) {
    if (!authorised(req, options)) return answer(unauthorised(req));
    if (!origin_allowed(req, options))
      throw Refusal{403, "requests from this origin are not allowed", "Origin"};
    return put_world(req, ctx, t.id, answer);
  }
  const std::shared_ptr<HostedWorld> world = ctx.worlds.find(t.id);
  if (!world) throw Refusal{404, "no world '" + std::string(t.id) + "'", "world"};
  if (is_get(req.method())) {
    if (options.token_reads && !may_steer(req, options, *world)) return answer(unauthorised(req));
    return get_world(req, ctx, *world, answer);
  }
  if (!may_steer(req, options, *world)) return answer(unauthorised(req));
  if (!origin_allowed(req, options))
    throw Refusal{403, "requests from this origin are not allowed", "Origin"};
  delete_world(req, ctx, *world, answer);
}

void serve_world_route(const Request& req, ServerContext& ctx, const Target& t,
                       const WorldRoute& route, const Reply& answer) {
  const ServerOptions& options = ctx.options;
  const std::shared_ptr<HostedWorld> world = ctx.worlds.find(t.id);
  if (!world) throw Refusal{404, "no world '" + std::string(t.id) + "'", "world"};
  const bool post = route.method == http::verb::post;
  if ((post || options.token_reads) && !may_steer(req, options, *world))
    return answer(unauthorised(req));
  if (post && !origin_allowed(req, options))
    throw Refusal{403, "requests from this origin are not allowed", "Origin"};
  // The world is busy from here until the answer is sent (or the handler throws): the guard
  // lives in the answer, which the command's completion holds while the simulation runs it.
  world->begin_request();
  const std::shared_ptr<void> busy(nullptr, [world](void*) { world->end_request(); });
  route.handler(req, ctx, *world, [busy, answer](Response res) { answer(std::move(res)); });
}

void dispatch(const Request& req, ServerContext& ctx, const Reply& answer) {
  const ServerOptions& options = ctx.options;
  const std::string_view path = path_of(req.target());
  const Target t = parse_target(path);
  std::string allow;
  const WorldRoute* world_route = nullptr;
  switch (t.kind) {
    case Target::Kind::none: break;
    case Target::Kind::server: allow = "GET, HEAD"; break;
    case Target::Kind::world: allow = "GET, HEAD, PUT, DELETE"; break;
    case Target::Kind::world_route:
      world_route = find_world_route(t.route, req.method(), allow);
      break;
  }
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
  const bool allowed = t.kind == Target::Kind::world_route
                           ? world_route != nullptr
                           : allow.find(std::string(to_string(req.method()))) != std::string::npos;
  if (!allowed) {
    Response res = error_response(req, 405, "method not allowed", "");
    res.set(http::field::allow, allow);
    return answer(std::move(res));
  }
  if (t.kind != Target::Kind::server && !valid_world_id(t.id))
    throw Refusal{400, "a world id is 1 to 64 of a-z, 0-9 and '-'", "id"};
  switch (t.kind) {
    case Target::Kind::server:
      if (options.token_reads && path != "/api/health" && !authorised(req, options))
        return answer(unauthorised(req));
      return t.server->handler(req, ctx, answer);
    case Target::Kind::world:
      return serve_world(req, ctx, t, answer);
    default:
      return serve_world_route(req, ctx, t, *world_route, answer);
  }
}

}  // namespace

bool token_matches(std::string_view given, std::string_view expected) {
  unsigned char diff = given.size() == expected.size() ? 0 : 1;
  for (std::size_t i = 0; i < expected.size(); ++i)
    diff |= static_cast<unsigned char>(expected[i] ^ (i < given.size() ? given[i] : 0));
  return diff == 0;
}

std::string_view bearer_token(const Request& req) {
  const std::string_view auth = req[http::field::authorization];
  constexpr std::string_view kScheme = "bearer ";
  if (auth.size() < kScheme.size()) return {};
  for (std::size_t i = 0; i < kScheme.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(auth[i])) != kScheme[i]) return {};
  return auth.substr(kScheme.size());
}

bool authorised(const Request& req, const ServerOptions& options) {
  return options.token.empty() || token_matches(bearer_token(req), options.token);
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

bool may_steer(const Request& req, const ServerOptions& options, const HostedWorld& world) {
  if (world.token().empty()) return authorised(req, options);
  const std::string_view given = bearer_token(req);
  return token_matches(given, world.token()) ||
         (!options.token.empty() && token_matches(given, options.token));
}

std::shared_ptr<HostedWorld> world_of_target(std::string_view target, ServerContext& ctx) {
  const Target t = parse_target(path_of(target));
  if (t.kind != Target::Kind::world_route && t.kind != Target::Kind::world) return nullptr;
  return ctx.worlds.find(t.id);
}

unsigned outcome_status(const CommandOutcome& outcome) {
  const auto* error = std::get_if<CommandError>(&outcome);
  if (!error) return 200;
  switch (error->failure) {
    case Failure::invalid: return 400;
    case Failure::not_found: return 404;
    case Failure::conflict: return 409;
    case Failure::unavailable: return 503;
    case Failure::internal: return 500;
  }
  return 500;
}

json outcome_json(const CommandOutcome& outcome) {
  struct Visitor {
    json operator()(const CommandError& e) const {
      return {{"error", e.message}, {"field", e.field}};
    }
    json operator()(const PausedState& p) const { return {{"ok", true}, {"paused", p.paused}}; }
    json operator()(const SceneReset& r) const { return {{"ok", true}, {"scene", r.scene}}; }
    json operator()(const IntegratorSet& i) const {
      return {{"ok", true}, {"integrator", std::string(to_string(i.integrator))}};
    }
    json operator()(const ImpulseApplied&) const { return {{"ok", true}}; }
    json operator()(const StepReport& r) const {
      json body{{"ok", true},           {"time", r.time},
                {"step", r.step},       {"steps_requested", r.requested},
                {"steps_done", r.done}, {"complete", r.stopped == nullptr}};
      if (r.stopped) body["stopped"] = r.stopped;
      return body;
    }
    json operator()(const SeekDone& d) const { return seek_json(d); }
    json operator()(const PlayState& p) const { return play_json(p); }
    json operator()(const HistoryReport& h) const { return history_json(h); }
    json operator()(const RecordingReport& r) const { return recording_json(*r.recording); }
    json operator()(const BodyAdded& b) const {
      return {{"ok", true}, {"body", b.body}, {"name", b.name}};
    }
  };
  return std::visit(Visitor{}, outcome);
}

void handle_api(const Request& req, ServerContext& ctx, Reply reply) {
  // Every response passes through here so that CORS headers are added in one place; it
  // may run after `req` is gone (on a simulation thread), so it copies what it needs.
  Reply answer = [cors = cors_origin(req, ctx.options), reply = std::move(reply)](Response res) {
    if (!cors.empty()) {
      res.set(http::field::access_control_allow_origin, cors);
      res.set(http::field::vary, "Origin");
    }
    reply(std::move(res));
  };
  try {
    dispatch(req, ctx, answer);
  } catch (const Refusal& r) {
    answer(error_response(req, r.status, r.message, r.field));
  } catch (const std::exception& e) {
    answer(error_response(req, 500, e.what(), ""));
  }
}

}  // namespace tumble::server
