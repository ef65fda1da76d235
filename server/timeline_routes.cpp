// Timeline, recording and body routes of a world (docs/protocol.md, "Timeline", "Recording",
// "Bodies"); the rest of the REST API is in rest_api.cpp.
#include <cmath>

#include "recording.hpp"
#include "request_limits.hpp"
#include "rest_routes.hpp"
#include "sim_loop.hpp"
#include "tumble/scene_io.hpp"
#include "worlds.hpp"

namespace tumble::server::rest {

using nlohmann::json;

namespace {

double speed_field(const json& body, double lo, double hi, bool optional) {
  if (!body.contains("speed")) {
    if (optional) return 1.0;
    throw Refusal{400, "missing field 'speed'", "speed"};
  }
  const json& speed = body["speed"];
  if (!speed.is_number()) throw Refusal{400, "speed must be a number", "speed"};
  const double f = speed.get<double>();
  if (!(f >= lo && f <= hi))
    throw Refusal{400, "speed must be in " + json(lo).dump() + ".." + json(hi).dump(), "speed"};
  return f;
}

}  // namespace

void post_seek(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"time", "step"});
  SeekCommand c;
  if (body.contains("time") == body.contains("step"))
    throw Refusal{400, "give exactly one of 'time' (s) and 'step'",
                  body.contains("time") ? "step" : "time"};
  if (body.contains("time")) {
    if (!body["time"].is_number()) throw Refusal{400, "time must be a number", "time"};
    c.time = body["time"].get<double>();
  } else {
    const json& step = body["step"];
    if (!step.is_number_integer() || (!step.is_number_unsigned() && step.get<std::int64_t>() < 0))
      throw Refusal{400, "step must be a non-negative integer", "step"};
    c.step = step.get<std::uint64_t>();
  }
  submit(world, req, c, reply);
}

void post_play(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"speed"});
  submit(world, req,
         PlayCommand{speed_field(body, SimLoop::kMinPlaySpeed, SimLoop::kMaxPlaySpeed, true)},
         reply);
}

void post_speed(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  const json body = parse_body(req);
  only_keys(body, {"speed"});
  submit(world, req,
         SpeedCommand{speed_field(body, SimLoop::kMinLiveSpeed, SimLoop::kMaxLiveSpeed, false)},
         reply);
}

void get_history(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  submit(world, req, HistoryCommand{}, reply);
}

void get_recording(const Request& req, ServerContext&, HostedWorld& world, const Reply& reply) {
  submit(world, req, RecordingCommand{}, reply);
}

// ---- Bodies (docs/protocol.md, "Bodies") -----------------------------------------------

void post_bodies(const Request& req, ServerContext& ctx, HostedWorld& world, const Reply& reply) {
  const json body = parse_body(req);
  for (const char* key : {"size", "mass", "position"}) required(body, key);
  AddBodyCommand c;
  try {
    c.definition = body_from_json(body);
  } catch (const SceneParseError& e) {
    throw Refusal{400, e.what(), e.field};
  }
  // A body may not arrive faster than an impulse may make one (SimLoop::kMaxSpeed, kMaxSpin).
  if (c.definition.velocity.norm() > SimLoop::kMaxSpeed)
    throw Refusal{400, "velocity: at most 1000 m/s", "velocity"};
  if (c.definition.angular_velocity.norm() > SimLoop::kMaxSpin)
    throw Refusal{400, "angular_velocity: at most 1000 rad/s", "angular_velocity"};
  c.named = body.contains("name");
  if (c.named && (c.definition.name.empty() || c.definition.name.size() > 64))
    throw Refusal{400, "name: 1 to 64 characters", "name"};
  c.max_bodies = static_cast<std::size_t>(ctx.options.max_bodies);
  const unsigned version = req.version();
  const bool keep_alive = req.keep_alive();
  world.sim().submit({std::move(c), [reply, version, keep_alive](CommandOutcome r) {
                        const unsigned status = outcome_status(r);
                        reply(json_response(version, keep_alive, status == 200 ? 201 : status,
                                            outcome_json(r)));
                      }});
}

}  // namespace tumble::server::rest
