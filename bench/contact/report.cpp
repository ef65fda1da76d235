/// contact, report: the `contact` section, bench/text/contact.md filled in with the table.
#include <cmath>

#include "contact/contact.hpp"
#include "report.hpp"
#include "text.hpp"

namespace tumble_bench::contact {
namespace {

std::vector<std::string> table_row(const Row& r) {
  return {"`" + r.scene + "`",
          r.engine,
          r.valid ? fmt(r.ms) : "did not run",
          r.engine == "tumble" ? "1" : (r.valid ? fmt(r.ratio) + "×" : "–"),
          std::isfinite(r.tower_drift) ? fmt(r.tower_drift) + " m" : "–",
          std::isfinite(r.penetration) ? fmt(r.penetration) + " m" : "–",
          std::isfinite(r.top_moved) ? fmt(r.top_moved) + " m" : "–",
          r.stands,
          r.asleep};
}

/// Notes on the runs: short timings, refusals, trouble in the sleeping run, steps alone.
std::string not_run(const Measurement& m) {
  std::vector<std::string> notes;
  for (const SceneResult& r : m.scenes)
    for (const Row& row : rows(m, r))
      if (!row.note.empty()) notes.push_back("`" + r.spec.name + "` on " + row.engine + ": " +
                                             row.note);
  return notes.empty() ? ""
                       : "Not run, not valid, timed short or run alone:\n\n" + bullet_list(notes);
}

std::string joined(const Measurement& m, const auto& item) {
  std::string s;
  for (const SceneResult& r : m.scenes) s += (s.empty() ? "" : ", ") + item(r);
  return s;
}

}  // namespace

void report(const Options& o, const Measurement& m, const fs::path& svg) {
  const auto v = recorded_values(o);
  std::vector<std::vector<std::string>> table;
  for (const SceneResult& r : m.scenes)
    for (const Row& row : rows(m, r)) table.push_back(table_row(row));
  std::string awake_notes;
  for (const Contender& c : m.engines)
    if (c.name != "tumble") awake_notes += (awake_notes.empty() ? "" : "; ") + c.name + ": " +
                                           c.keep_awake_note;
  const Fields f{
      {"date", v.count("date") ? v.at("date") : "unknown"},
      {"engine_commit", v.count("engine_commit") ? v.at("engine_commit") : "unknown"},
      {"quick", o.quick ? " --quick" : ""},
      {"partial", partial_note(o)},
      {"reps", std::to_string(m.reps)},
      {"peer_awake_notes", awake_notes.empty() ? "no peers built in" : awake_notes},
      {"timed_steps", joined(m, [](const SceneResult& r) {
         return "`" + r.spec.name + "` " + std::to_string(r.timed_steps);
       })},
      {"sleep_caps", joined(m, [](const SceneResult& r) {
         return "`" + r.spec.name + "` " + fmt(static_cast<double>(r.spec.sleep_cap) * r.dt) + " s";
       })},
      {"behaviour_budgets", joined(m, [](const SceneResult& r) {
         return "`" + r.spec.name + "` " + fmt(r.spec.behaviour_budget) + " s";
       })},
      {"stands_tolerance", fmt(kStandsTolerance * 100.0) + " cm"},
      {"plot", image_link(o, svg, "contact: ms per step on every engine")},
      {"table", md_table({"scene", "engine", "ms per step", "ratio", "tower drift (60 s)",
                          "max penetration", "top box moved", "stands", "asleep at"},
                         table)},
      {"csv", file_link(o, o.out / "contact.csv")},
      {"not_run", not_run(m)},
  };
  write_section(o, "contact", fill_template("contact", f));
}

}  // namespace tumble_bench::contact
