#pragma once
/// The REST routes of docs/protocol.md (/api/…, /metrics): parse and validate at the
/// boundary, then answer from the latest snapshot or through a command to the simulation.
/// Never throws.
#include <functional>
#include <string_view>

#include <boost/beast/http.hpp>

#include "context.hpp"

namespace tumble::server {

using Request = boost::beast::http::request<boost::beast::http::string_body>;
using Response = boost::beast::http::response<boost::beast::http::string_body>;
/// Receives the response, once; may be called on the simulation thread.
using Reply = std::function<void(Response)>;

/// True for targets the API owns (/api, /api/…, /metrics).
bool is_api_target(std::string_view path);

/// True when a browser request's Origin may act on this server: no Origin header (not a
/// browser), the server's own origin (http://<Host>), or --allowed-origin ("*": any).
bool origin_allowed(const Request& request, const ServerOptions& options);

/// True when `given` equals `expected`, in time that depends only on `expected`'s length.
bool token_matches(std::string_view given, std::string_view expected);

/// The token of an "Authorization: Bearer <token>" header ("" when there is none).
std::string_view bearer_token(const Request& request);

/// True when no --token is set or the request carries "Authorization: Bearer <token>".
bool authorised(const Request& request, const ServerOptions& options);

/// True when the request may steer `world`: its bearer token is the world's write token or
/// the server's --token (the default world, which has no token of its own: authorised()).
bool may_steer(const Request& request, const ServerOptions& options, const HostedWorld& world);

/// The world an API target addresses (the default world for unprefixed routes), or null for
/// server routes and unknown worlds.
std::shared_ptr<HostedWorld> world_of_target(std::string_view target, ServerContext& ctx);

/// The HTTP status of a command's outcome (200, or the 4xx/5xx of its failure).
unsigned outcome_status(const CommandOutcome& outcome);

/// The JSON body of a command's outcome (docs/protocol.md).
nlohmann::json outcome_json(const CommandOutcome& outcome);

/// Shortest scene dt accepted over REST, s: below it a second of simulated time costs a
/// million steps or more (a busy loop for nothing).
inline constexpr double kMinDt = 1e-6;

/// A JSON response {"error": message, "field": field}.
Response error_response(const Request& request, unsigned status, std::string_view message,
                        std::string_view field);

/// Handles an API request; `reply` gets the response (at once or when the command is done).
void handle_api(const Request& request, ServerContext& ctx, Reply reply);

}  // namespace tumble::server
