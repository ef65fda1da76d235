#include "recording.hpp"

#include <bit>
#include <cmath>
#include <cstring>

#include "tumble/scene_io.hpp"

namespace tumble::server {

using nlohmann::json;

namespace {

json vec_json(const Vec3& v) { return json::array({v.x(), v.y(), v.z()}); }

std::uint64_t fnv1a(std::uint64_t hash, double value) {
  unsigned char bytes[sizeof(double)];
  std::memcpy(bytes, &value, sizeof(double));
  if constexpr (std::endian::native == std::endian::big)
    for (std::size_t i = 0; i < sizeof(double) / 2; ++i) std::swap(bytes[i], bytes[7 - i]);
  for (unsigned char b : bytes) hash = (hash ^ b) * 0x100000001b3ull;
  return hash;
}

// ---- Parsing: every refusal names its field ---------------------------------------------

const json& field(const json& j, const char* key, const std::string& prefix) {
  const auto it = j.find(key);
  if (it == j.end()) throw RecordingError(prefix + key, std::string("missing field '") + key + "'");
  return *it;
}

std::uint64_t unsigned_field(const json& j, const char* key, const std::string& prefix) {
  const json& v = field(j, key, prefix);
  if (!v.is_number_unsigned() && !(v.is_number_integer() && v.get<std::int64_t>() >= 0))
    throw RecordingError(prefix + key, "expected a non-negative integer");
  return v.get<std::uint64_t>();
}

double number_field(const json& j, const char* key, const std::string& prefix) {
  const json& v = field(j, key, prefix);
  if (!v.is_number() || !std::isfinite(v.get<double>()))
    throw RecordingError(prefix + key, "expected a finite number");
  return v.get<double>();
}

Vec3 vec_field(const json& v, const std::string& name) {
  if (!v.is_array() || v.size() != 3) throw RecordingError(name, "expected an array of 3 numbers");
  Vec3 out;
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>()))
      throw RecordingError(name, "expected an array of 3 finite numbers");
    out[i] = v[i].get<double>();
  }
  return out;
}

LoggedCommand parse_command(const json& c, const std::string& prefix, std::size_t& bodies) {
  if (!c.is_object()) throw RecordingError(prefix.substr(0, prefix.size() - 1), "expected an object");
  LoggedCommand out;
  out.step = unsigned_field(c, "step", prefix);
  out.time = c.contains("time") ? number_field(c, "time", prefix) : 0.0;
  const json& kind = field(c, "kind", prefix);
  const std::string name = kind.is_string() ? kind.get<std::string>() : std::string();
  if (name == "reset") {
    out.kind = LoggedKind::reset;
    if (c.contains("scene") && c["scene"].is_string()) out.scene = c["scene"].get<std::string>();
  } else if (name == "pause") {
    out.kind = LoggedKind::pause;
  } else if (name == "resume") {
    out.kind = LoggedKind::resume;
  } else if (name == "integrator") {
    out.kind = LoggedKind::integrator;
    const json& i = field(c, "integrator", prefix);
    const auto parsed = i.is_string() ? parse_integrator(i.get<std::string>()) : std::nullopt;
    if (!parsed) throw RecordingError(prefix + "integrator", "unknown integrator");
    out.integrator = *parsed;
  } else if (name == "impulse") {
    out.kind = LoggedKind::impulse;
    const std::uint64_t body = unsigned_field(c, "body", prefix);
    if (body >= bodies)
      throw RecordingError(prefix + "body", "no body with index " + std::to_string(body));
    out.body = static_cast<BodyId>(body);
    out.impulse = vec_field(field(c, "impulse", prefix), prefix + "impulse");
    if (c.contains("point") && !c["point"].is_null())
      out.point = vec_field(c["point"], prefix + "point");
  } else if (name == "add_body") {
    out.kind = LoggedKind::add_body;
    const std::uint64_t body = unsigned_field(c, "body", prefix);
    if (body != bodies)
      throw RecordingError(prefix + "body", "expected " + std::to_string(bodies) +
                                                " (the next body index)");
    out.body = static_cast<BodyId>(body);
    try {
      out.definition = std::make_shared<const BodyDef>(body_from_json(field(c, "definition", prefix)));
    } catch (const SceneParseError& e) {
      throw RecordingError(prefix + "definition" + (e.field.empty() ? "" : "." + e.field),
                           e.what());
    }
    ++bodies;
  } else {
    throw RecordingError(prefix + "kind",
                         "expected reset, impulse, integrator, pause, resume or add_body");
  }
  return out;
}

}  // namespace

const char* to_string(LoggedKind kind) {
  switch (kind) {
    case LoggedKind::reset: return "reset";
    case LoggedKind::impulse: return "impulse";
    case LoggedKind::integrator: return "integrator";
    case LoggedKind::pause: return "pause";
    case LoggedKind::resume: return "resume";
    case LoggedKind::add_body: return "add_body";
  }
  return "?";
}

void apply_logged(World& world, const LoggedCommand& c) {
  switch (c.kind) {
    case LoggedKind::impulse:
      if (c.point)
        world.apply_impulse(c.body, c.impulse, *c.point);
      else
        world.apply_impulse(c.body, c.impulse);
      return;
    case LoggedKind::integrator:
      world.set_integrator(c.integrator);
      return;
    case LoggedKind::add_body: {
      if (!c.definition) throw InvalidInput("add_body without a definition");
      if (c.body != world.bodies().size())
        throw InvalidInput("add_body: the world has " + std::to_string(world.bodies().size()) +
                           " bodies, the log expects id " + std::to_string(c.body));
      world.add_body(*c.definition);
      return;
    }
    case LoggedKind::reset:
    case LoggedKind::pause:
    case LoggedKind::resume:
      return;
  }
}

std::uint64_t state_digest(const World& world) {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  for (const Body& b : world.bodies()) {
    for (int i = 0; i < 3; ++i) hash = fnv1a(hash, b.s.x[i]);
    for (int i = 0; i < 9; ++i) hash = fnv1a(hash, b.s.R.data()[i]);
    for (int i = 0; i < 3; ++i) hash = fnv1a(hash, b.s.P[i]);
    for (int i = 0; i < 3; ++i) hash = fnv1a(hash, b.s.L[i]);
  }
  return hash;
}

std::string digest_hex(std::uint64_t digest) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out(16, '0');
  for (int i = 15; i >= 0; --i, digest >>= 4) out[static_cast<std::size_t>(i)] = kHex[digest & 0xf];
  return out;
}

json logged_json(const LoggedCommand& c) {
  json j{{"step", c.step}, {"time", c.time}, {"kind", to_string(c.kind)}};
  switch (c.kind) {
    case LoggedKind::impulse:
      j["body"] = c.body;
      j["impulse"] = vec_json(c.impulse);
      if (c.point) j["point"] = vec_json(*c.point);
      break;
    case LoggedKind::integrator:
      j["integrator"] = std::string(to_string(c.integrator));
      break;
    case LoggedKind::reset:
      j["scene"] = c.scene;
      break;
    case LoggedKind::add_body:
      j["body"] = c.body;
      j["definition"] = c.definition ? body_json(*c.definition) : json();
      break;
    case LoggedKind::pause:
    case LoggedKind::resume:
      break;
  }
  return j;
}

json body_json(const BodyDef& body) {
  Scene scene;
  scene.bodies.push_back(body);
  return scene_to_json(scene)["bodies"][0];
}

// scene_io parses bodies only within a scene: the body is parsed as the one body of an
// otherwise default scene, and the field is named relative to it.
BodyDef body_from_json(const json& body) {
  try {
    Scene scene = scene_from_json(json{{"bodies", json::array({body})}});
    return std::move(scene.bodies.at(0));
  } catch (const SceneParseError& e) {
    static const std::string kAt = "bodies[0]";
    std::string f = e.field;
    std::string message = e.what();
    if (f.starts_with(kAt)) {
      f = f.substr(kAt.size());
      if (f.starts_with(".")) f = f.substr(1);
    }
    if (message.starts_with(kAt + ".")) message = message.substr(kAt.size() + 1);
    else if (message.starts_with(kAt)) message = "body" + message.substr(kAt.size());
    throw SceneParseError(f, message);
  }
}

json recording_json(const Recording& r) {
  json commands = json::array();
  for (const LoggedCommand& c : r.commands) commands.push_back(logged_json(c));
  return {{"format", "tumble-recording"},
          {"version", kRecordingVersion},
          {"scene", scene_to_json(r.scene)},
          {"integrator", std::string(to_string(r.scene.world.integrator))},
          {"dt", r.scene.world.dt},
          {"commands", std::move(commands)},
          {"final_step", r.final_step},
          {"final_time", r.final_time},
          {"digest_algorithm", "fnv1a64-body-state"},
          {"digest", digest_hex(r.digest)}};
}

Recording parse_recording(const json& d) {
  if (!d.is_object()) throw RecordingError("", "a recording is a JSON object");
  const json& format = field(d, "format", "");
  if (format != "tumble-recording")
    throw RecordingError("format", "expected \"tumble-recording\"");
  if (field(d, "version", "") != kRecordingVersion)
    throw RecordingError("version", "expected " + std::to_string(kRecordingVersion));
  Recording r;
  try {
    r.scene = scene_from_json(field(d, "scene", ""));
  } catch (const SceneParseError& e) {
    throw RecordingError(e.field.empty() ? "scene" : "scene." + e.field, e.what());
  }
  if (d.contains("dt") && (!d["dt"].is_number() || d["dt"].get<double>() != r.scene.world.dt))
    throw RecordingError("dt", "differs from scene.dt");
  r.final_step = unsigned_field(d, "final_step", "");
  if (r.final_step > kMaxRecordingSteps)
    throw RecordingError("final_step", "more than " + std::to_string(kMaxRecordingSteps) + " steps");
  r.final_time = d.contains("final_time") ? number_field(d, "final_time", "") : 0.0;
  const json& commands = field(d, "commands", "");
  if (!commands.is_array()) throw RecordingError("commands", "expected an array");
  if (commands.size() > kMaxRecordingCommands)
    throw RecordingError("commands", "more than " + std::to_string(kMaxRecordingCommands));
  std::size_t bodies = r.scene.bodies.size();
  for (std::size_t i = 0; i < commands.size(); ++i) {
    const std::string prefix = "commands[" + std::to_string(i) + "].";
    LoggedCommand c = parse_command(commands[i], prefix, bodies);
    if (c.step > r.final_step) throw RecordingError(prefix + "step", "after final_step");
    if (!r.commands.empty() && c.step < r.commands.back().step)
      throw RecordingError(prefix + "step", "steps must not decrease");
    r.commands.push_back(std::move(c));
  }
  const json& digest = field(d, "digest", "");
  const std::string hex = digest.is_string() ? digest.get<std::string>() : std::string();
  if (hex.size() != 16 || hex.find_first_not_of("0123456789abcdef") != std::string::npos)
    throw RecordingError("digest", "expected 16 lowercase hex digits");
  r.digest = std::stoull(hex, nullptr, 16);
  return r;
}

ReplayResult replay(const Recording& r, unsigned threads) {
  World world(r.scene);
  world.set_threads(threads);
  std::size_t next = 0;
  for (;;) {
    while (next < r.commands.size() && r.commands[next].step == world.step_count()) {
      try {
        apply_logged(world, r.commands[next]);
      } catch (const InvalidInput& e) {
        throw RecordingError("commands[" + std::to_string(next) + "]", e.what());
      }
      ++next;
    }
    if (world.step_count() >= r.final_step) break;
    world.step();
  }
  return {world.step_count(), world.time(), state_digest(world)};
}

}  // namespace tumble::server
