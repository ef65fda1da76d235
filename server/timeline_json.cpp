#include "timeline_json.hpp"

namespace tumble::server {

using nlohmann::json;

namespace {

json point_json(const TimelinePoint& p) { return {{"time", p.time}, {"step", p.step}}; }

}  // namespace

json history_json(const HistoryReport& r) {
  const TimelineSummary& t = r.timeline;
  json commands = json::array();
  for (const LoggedCommand& c : t.commands) commands.push_back(logged_json(c));
  json impacts = json::array();
  for (const ImpactMarker& m : t.impacts)
    impacts.push_back({{"step", m.step}, {"time", m.time}, {"impacts", m.impacts}});
  return {{"enabled", t.enabled},
          {"from", point_json(t.from)},
          {"to", point_json(t.to)},
          {"at", point_json(r.at)},
          {"live", r.live},
          {"playing", r.playing},
          {"paused", r.paused},
          {"speed", r.speed},
          {"checkpoints", t.checkpoints},
          {"checkpoint_interval", t.interval},
          {"bytes", t.bytes},
          {"bytes_limit", r.bytes_limit},
          {"history_s", r.history_s},
          {"commands", std::move(commands)},
          {"commands_truncated", t.commands_truncated},
          {"impacts", std::move(impacts)}};
}

json seek_json(const SeekDone& d) { return {{"ok", true}, {"time", d.time}, {"step", d.step}}; }

json play_json(const PlayState& s) {
  return {{"ok", true},          {"time", s.time},     {"step", s.step},
          {"playing", s.playing}, {"paused", s.paused}, {"speed", s.speed}};
}

}  // namespace tumble::server
