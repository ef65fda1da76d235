/// pile-precision, report: the `pile_precision` section, bench/text/pile_precision.md filled
/// in with the table.
#include <algorithm>
#include <cmath>
#include <utility>

#include "pile_precision/pile_precision.hpp"
#include "report.hpp"
#include "text.hpp"

namespace tumble_bench::pile_precision {
namespace {

std::vector<std::string> table_row(const Point& p, double tumble_cpu) {
  if (!std::isfinite(p.cpu_per_sim_s)) return {dt_label(p.dt), p.engine, "did not run", "–",
                                               "–", "–", "–"};
  return {dt_label(p.dt),
          p.engine,
          fmt(p.cpu_per_sim_s),
          fmt(p.cpu_per_sim_s / tumble_cpu) + "×",
          fmt(p.deepest * 100.0) + " cm",
          fmt(p.deepest_at) + " s",
          fmt(p.time_over) + " s"};
}

/// Refusals and trouble (once per engine and message, with the step sizes it came at), and
/// runs stopped by the CPU budget.
std::string notes(const Measurement& m) {
  std::vector<std::pair<std::string, std::string>> troubles;  // (what, step sizes)
  std::vector<std::string> items;
  for (const Point& p : m.points) {
    if (!p.trouble.empty()) {
      const std::string what = p.engine + ": " + p.trouble;
      auto seen = std::find_if(troubles.begin(), troubles.end(),
                               [&](const auto& t) { return t.first == what; });
      if (seen == troubles.end()) troubles.emplace_back(what, dt_label(p.dt));
      else seen->second += ", " + dt_label(p.dt);
    } else if (static_cast<double>(p.steps) * p.dt < m.duration - p.dt / 2) {
      items.push_back(p.engine + " at dt = " + dt_label(p.dt) + ": stopped by the CPU budget at " +
                      fmt(static_cast<double>(p.steps) * p.dt) + " s");
    }
  }
  for (const auto& [what, dts] : troubles) items.push_back("(dt = " + dts + ") " + what);
  return items.empty() ? "" : "Not run, not valid or cut short:\n\n" + bullet_list(items);
}

/// What each peer's run costs at the overlap Tumble keeps at the largest dt.
std::string matched(const Measurement& m) {
  const Point& tumble = m.points.front();  // Tumble at the largest dt runs first
  if (!std::isfinite(tumble.cpu_per_sim_s)) return "";
  std::vector<std::string> items;
  for (const std::string& engine : m.engines) {
    if (engine == tumble.engine || engine == kBoundedName) continue;
    bool at_most = false;
    const double cpu = cpu_at_depth(m, engine, tumble.deepest, &at_most);
    if (std::isnan(cpu)) {
      const bool ran = std::any_of(m.points.begin(), m.points.end(), [&](const Point& p) {
        return p.engine == engine && std::isfinite(p.cpu_per_sim_s);
      });
      if (ran) items.push_back(engine + ": deeper at every dt down to " + dt_label(m.dts.back()));
      continue;
    }
    items.push_back(engine + ": " + (at_most ? "at most " : "about ") + fmt(cpu) +
                    " CPU s per simulated s, " + fmt(cpu / tumble.cpu_per_sim_s) + "× Tumble's");
  }
  if (items.empty()) return "";
  return "At Tumble's own overlap at dt = " + dt_label(tumble.dt) + " (" +
         fmt(tumble.deepest * 100.0) + " cm, " + fmt(tumble.cpu_per_sim_s) +
         " CPU s per simulated s), what each peer's run costs (its curve interpolated on the "
         "log–log axes between the two step sizes that bracket that overlap):\n\n" +
         bullet_list(items);
}

}  // namespace

void report(const Options& o, const Measurement& m, const fs::path& svg) {
  const auto v = recorded_values(o);
  std::vector<std::vector<std::string>> table;
  double tumble_cpu = NAN;
  for (const Point& p : m.points) {
    if (p.engine == m.engines.front()) tumble_cpu = p.cpu_per_sim_s;  // Tumble runs first
    table.push_back(table_row(p, tumble_cpu));
  }
  std::string dts;
  for (const double dt : m.dts) dts += (dts.empty() ? "" : ", ") + dt_label(dt);
  const Fields f{
      {"date", v.count("date") ? v.at("date") : "unknown"},
      {"engine_commit", v.count("engine_commit") ? v.at("engine_commit") : "unknown"},
      {"quick", o.quick ? " --quick" : ""},
      {"duration", fmt(m.duration)},
      {"dts", dts},
      {"budget", fmt(m.budget)},
      {"bound", fmt(kBound * 100.0) + " cm"},
      {"initial", fmt(m.initial * 100.0) + " cm"},
      {"plot", image_link(o, svg, "pile: deepest overlap against CPU time")},
      {"table", md_table({"dt (s)", "engine", "CPU s per simulated s", "time / Tumble's at this dt",
                          "deepest overlap", "at", "time deeper than " + fmt(kBound * 100.0) +
                                                      " cm"},
                         table)},
      {"csv", file_link(o, o.out / "pile_precision.csv")},
      {"notes", notes(m)},
      {"matched", matched(m)},
  };
  write_section(o, "pile_precision", fill_template("pile_precision", f));
}

}  // namespace tumble_bench::pile_precision
