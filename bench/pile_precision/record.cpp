/// pile-precision, record: pile_precision.csv, the headline values in summary.csv and the
/// log–log plot of deepest overlap against CPU time per simulated second.
#include <algorithm>
#include <cmath>
#include <iostream>

#include "pile_precision/pile_precision.hpp"
#include "report.hpp"
#include "work_precision/work_precision.hpp"

namespace tumble_bench::pile_precision {
namespace {

void print(const Point& p) {
  std::cerr << "  " << p.engine << " dt = " << dt_label(p.dt) << ": " << fmt(p.cpu_per_sim_s)
            << " CPU s per simulated s, deepest " << fmt(p.deepest) << " m at "
            << fmt(p.deepest_at) << " s, " << fmt(p.time_over) << " s deeper than "
            << fmt(kBound) << " m"
            << (p.trouble.empty() ? "" : " [" + p.trouble.substr(0, 100) + "]") << '\n';
}

/// Headline values: Tumble's point at the scene's own dt, and the largest dt (cheapest run)
/// at which each engine kept every overlap within kBound.
void record_headlines(const Options& o, const Measurement& m) {
  for (const std::string& engine : m.engines) {
    const std::string k = "pile_precision." + engine + ".";
    double within_dt = NAN, within_cpu = NAN;
    for (const Point& p : m.points) {
      if (p.engine != engine || !p.trouble.empty()) continue;
      if (p.dt == m.dts.front()) {
        record_value(o, k + "deepest_m", fmt(p.deepest, 6));
        record_value(o, k + "cpu_per_sim_s", fmt(p.cpu_per_sim_s, 4));
      }
      if (p.deepest <= kBound && !(p.dt <= within_dt)) {
        within_dt = p.dt;
        within_cpu = p.cpu_per_sim_s;
      }
    }
    record_value(o, k + "dt_within_bound", std::isfinite(within_dt) ? dt_label(within_dt) : "none");
    record_value(o, k + "cpu_within_bound", fmt(within_cpu, 4));
    // This engine's cost at the overlap Tumble keeps at the largest dt, over Tumble's cost.
    const Point& tumble = m.points.front();
    bool at_most = false;
    const double cpu = cpu_at_depth(m, engine, tumble.deepest, &at_most);
    record_value(o, k + "cpu_ratio_at_tumble_depth", fmt(cpu / tumble.cpu_per_sim_s, 4));
  }
}

}  // namespace

fs::path record(const Options& o, const Measurement& m) {
  {
    Csv out(o.out / "pile_precision.csv",
            {"engine", "dt", "steps", "cpu_s_per_sim_s", "deepest_m", "deepest_at_s",
             "time_deeper_than_bound_s", "bound_m", "trouble", "dt_label"});
    for (const Point& p : m.points) {
      out.row() << p.engine << p.dt << p.steps << p.cpu_per_sim_s << p.deepest << p.deepest_at
                << p.time_over << kBound << p.trouble << dt_label(p.dt);
      print(p);
    }
  }
  record_headlines(o, m);
  std::vector<std::string> curves;  // the engines that ran at some dt
  for (const std::string& e : m.engines)
    if (std::any_of(m.points.begin(), m.points.end(),
                    [&](const Point& p) { return p.engine == e && p.trouble.empty(); }))
      curves.push_back(e);
  const std::string script =
      wp::log_plot("pile_precision.csv", "CPU s per simulated second", "deepest overlap (m)", 4,
                   5, curves, 1, "pile: deepest overlap against run time, dt = 1/60 ... 1/480") +
      ", \\\n     " + fmt(kBound) + " with lines dt 2 lc 'gray' title '1 cm', \\\n" +
      "     'pile_precision.csv' skip 1 using 4:5:(strcol(10)) with labels offset char 1.5,0.6 "
      "font ',9' notitle\n";  // each point's dt
  return plot(o, "pile_precision", script);
}

}  // namespace tumble_bench::pile_precision
