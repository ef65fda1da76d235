/// contact: the table rows derived from a measurement, shared by the CSV and the Markdown.
#include <cmath>

#include "contact/contact.hpp"

namespace tumble_bench::contact {
namespace {

std::string sleep_text(const Contender& c, const Behaviour& b) {
  if (std::isfinite(b.asleep_at)) return fmt(b.asleep_at) + " s";
  if (!c.sleeps) return "no sleeping";
  if (std::isfinite(b.end_time)) return "> " + fmt(b.end_time) + " s";
  return "–";
}

std::string short_timing_note(const SceneResult& r, const EngineResult& e) {
  if (e.steps_done <= 0 || e.steps_done >= r.timed_steps) return {};
  return "timed over its first " + std::to_string(e.steps_done) + " of " +
         std::to_string(r.timed_steps) + " steps (CPU budget " + fmt(r.spec.budget) + " s)";
}

/// A threaded Tumble ran some steps on the calling thread alone (held up, or far cores).
std::string alone_note(const SceneResult& r, const EngineResult& e) {
  if (e.steps_alone <= 0) return {};
  return std::to_string(e.steps_alone) + " of its " + std::to_string(r.timed_steps) +
         " timed steps on the calling thread alone in one repetition (its threads held up on "
         "a machine busier than its cores, or cores far apart: docs/engine.md, \"Threads\")";
}

/// The first thing that went wrong: a refusal, then trouble in the sleeping or the awake run.
std::string trouble_of(const SceneResult& r, const EngineResult& e) {
  if (!e.refused.empty()) return e.refused;
  if (!e.sleeping.trouble.empty()) return e.sleeping.trouble;
  if (r.spec.name == "tower") return e.tower_awake.trouble;
  return {};
}

}  // namespace

std::vector<Row> rows(const Measurement& m, const SceneResult& r) {
  std::vector<Row> out;
  const double tumble_ms = median(r.engine.at("tumble").ms);
  for (const Contender& c : m.engines) {
    const EngineResult& e = r.engine.at(c.name);
    Row row;
    row.scene = r.spec.name;
    row.engine = c.name;
    const std::string trouble = trouble_of(r, e);
    const double ms = median(e.ms);
    row.valid = std::isfinite(ms) && trouble.empty();
    row.ms = row.valid || c.name == "tumble" ? ms : NAN;
    row.ratio = c.name == "tumble" ? 1.0 : (row.valid ? ms / tumble_ms : NAN);
    // A threaded Tumble's ratio is its speed-up: one thread's time / its own, both by the
    // wall clock (one thread's CPU time would leave out the machine's noise on its side only).
    if (c.threads > 1 && row.valid) row.ratio = median(r.engine.at("tumble").wall_ms) / ms;
    const bool tower = r.spec.name == "tower";
    row.tower_drift = tower ? e.tower_awake.drift : NAN;
    // Deepest penetration: the sleeping run, and for the tower the 60 s awake run too.
    row.penetration = tower ? std::max(e.sleeping.penetration, e.tower_awake.penetration)
                            : e.sleeping.penetration;
    row.top_moved = r.spec.stack ? e.sleeping.top_moved : NAN;
    row.stands = !r.spec.stack || !std::isfinite(row.top_moved) ? "–"
                 : row.top_moved <= kStandsTolerance             ? "yes"
                                                                 : "no";
    if (row.stands == "no") row.stands += " (from " + fmt(e.sleeping.top_left_at) + " s)";
    // A run cut short by its CPU budget only vouches for the time it covered.
    const double cap_s = static_cast<double>(r.spec.sleep_cap) * r.dt;
    if (row.stands == "yes" && !std::isfinite(e.sleeping.asleep_at) &&
        e.sleeping.end_time < cap_s - 1e-9)
      row.stands += " (first " + fmt(e.sleeping.end_time) + " s)";
    row.asleep = sleep_text(c, e.sleeping);
    if (!trouble.empty()) {
      row.note = trouble;
    } else {
      const std::string timing = short_timing_note(r, e), alone = alone_note(r, e);
      row.note = timing + (timing.empty() || alone.empty() ? "" : "; ") + alone;
    }
    out.push_back(row);
  }
  return out;
}

}  // namespace tumble_bench::contact
