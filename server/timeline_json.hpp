#pragma once
/// JSON of the timeline's outcomes (docs/protocol.md, "Timeline"): what rest_api answers to
/// GET …/history, POST …/seek, …/play, …/speed. Pure functions; thread-safe.
#include <nlohmann/json.hpp>

#include "commands.hpp"

namespace tumble::server {

/// The GET …/history document.
nlohmann::json history_json(const HistoryReport& report);

/// The answer to POST …/seek: {"ok": true, "time", "step"}.
nlohmann::json seek_json(const SeekDone& done);

/// The answer to POST …/play and …/speed: {"ok", "time", "step", "playing", "paused", "speed"}.
nlohmann::json play_json(const PlayState& state);

}  // namespace tumble::server
