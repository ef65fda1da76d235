#pragma once
/// What the REST route files share (rest_api.cpp, timeline_routes.cpp): the refusal thrown at
/// the boundary, JSON responses, body parsers and command submission. Internal to the server
/// target; every function is thread-safe (no shared state).
#include <initializer_list>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "rest_api.hpp"

namespace tumble::server::rest {

/// A request refused at the boundary (thrown by the parsers, caught in handle_api).
struct Refusal {
  unsigned status;      ///< HTTP status (4xx).
  std::string message;  ///< The "error" text.
  std::string field;    ///< The "field" named ("" for none).
};

/// Largest impulse component accepted, N·s.
inline constexpr double kMaxImpulse = 1e6;
/// Largest point coordinate accepted, m (the scene's own position bound).
inline constexpr double kMaxPoint = 1e6;

/// A JSON response with the house headers (no-store, application/json).
Response json_response(unsigned version, bool keep_alive, unsigned status,
                       const nlohmann::json& body);
/// A 200 JSON response to `req`.
Response ok(const Request& req, const nlohmann::json& body);
/// The request body as a JSON object (bounded depth, no NUL); throws Refusal.
nlohmann::json parse_body(const Request& req);
/// Throws a 400 Refusal naming the first key of `j` not in `keys`.
void only_keys(const nlohmann::json& j, std::initializer_list<std::string_view> keys);
/// `j[key]`, or a 400 Refusal "missing field".
const nlohmann::json& required(const nlohmann::json& j, const char* key);
/// Three finite numbers within ±limit, or a 400 Refusal naming `field`.
Vec3 finite_vec3(const nlohmann::json& j, const char* field, double limit);
/// Submits `kind` to the world's simulation; the outcome becomes the HTTP reply.
void submit(HostedWorld& world, const Request& req, CommandKind kind, const Reply& reply);

/// POST …/seek {"time"|"step"} (timeline_routes.cpp).
void post_seek(const Request& req, ServerContext& ctx, HostedWorld& world, const Reply& reply);
/// POST …/play {"speed"?}.
void post_play(const Request& req, ServerContext& ctx, HostedWorld& world, const Reply& reply);
/// POST …/speed {"speed"}.
void post_speed(const Request& req, ServerContext& ctx, HostedWorld& world, const Reply& reply);
/// GET …/history.
void get_history(const Request& req, ServerContext& ctx, HostedWorld& world, const Reply& reply);
/// GET …/recording.
void get_recording(const Request& req, ServerContext& ctx, HostedWorld& world,
                   const Reply& reply);
/// POST …/bodies {body definition}: adds a body (201).
void post_bodies(const Request& req, ServerContext& ctx, HostedWorld& world, const Reply& reply);

}  // namespace tumble::server::rest
