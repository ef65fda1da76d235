/// peers, report: the `peers` section, bench/text/peers.md filled in with the tables.
#include <cmath>

#include "peers/peers.hpp"
#include "report.hpp"
#include "text.hpp"

namespace tumble_bench::peers {
namespace {

std::string settings() {
  std::vector<std::string> items;
  for (const PeerEngine& p : available_peers())
    items.push_back("**" + p.name + "** " + p.version + ": " + p.settings);
#ifdef TUMBLE_BENCH_HAVE_MUJOCO
  items.push_back("**mujoco-rk4**: as `mujoco` with integrator=\"RK4\" (used for `tumble` and "
                  "`bounce` only)");
#endif
  items.push_back("**tumble**: the scene's own settings, integrator `exact`, TOI `root`");
  return bullet_list(items);
}

/// Errors at dt = 1/30 and 1/120 per engine.
std::string tumble_table(const Measurement& m) {
  std::vector<std::vector<std::string>> rows;
  for (const Contender& c : m.all) {
    std::vector<std::string> row{c.name};
    for (const TumbleRun& r : m.tumble)
      if (r.engine == c.name && (std::fabs(r.dt - 1.0 / 30.0) < 1e-12 ||
                                 std::fabs(r.dt - 1.0 / 120.0) < 1e-12))
        row.push_back(fmt(r.err));
    rows.push_back(row);
  }
  return md_table({"engine", "error at dt = 1/30 (rad)", "error at dt = 1/120 (rad)"}, rows);
}

std::string bounce_table(const Measurement& m) {
  std::vector<std::vector<std::string>> rows;
  for (const BounceRun& r : m.bounce)
    rows.push_back({r.engine, fmt(r.apex[0], 6), fmt(r.apex[1], 6), fmt(r.apex[2], 6),
                    fmt(r.err)});
  return md_table({"engine", "apex 1 (m)", "apex 2 (m)", "apex 3 (m)", "apex 1 error (m)"}, rows);
}

std::string throughput_table(const Measurement& m) {
  std::vector<std::string> header{"N", "shape", "tumble ns per body-step"};
  for (const Contender& c : m.fast)
    if (c.name != "tumble") header.push_back(c.name + " ns per body-step (ratio)");
  std::vector<std::vector<std::string>> rows;
  for (const auto& [key, runs] : m.ns.at("tumble")) {
    const double t = median(runs);
    std::vector<std::string> row{std::to_string(key.first), to_string(key.second), fmt(t)};
    for (const Contender& c : m.fast) {
      if (c.name == "tumble") continue;
      const double v = median(m.ns.at(c.name).at(key));
      row.push_back(std::isfinite(v) ? fmt(v) + " (" + fmt(v / t) + "×)" : "did not run");
    }
    rows.push_back(row);
  }
  return md_table(header, rows);
}

std::string skip_table(const Measurement& m) {
  const double t = median(m.skip_ms.at("tumble"));
  std::vector<std::vector<std::string>> rows;
  for (const Contender& c : m.fast) {
    const double v = median(m.skip_ms.at(c.name));
    rows.push_back({c.name, fmt(v), c.name == "tumble" ? "1" : fmt(v / t)});
  }
  return md_table({"engine", "skip ms per step", "ratio"}, rows);
}

std::string not_run(const Measurement& m) {
  std::vector<std::string> items;
  for (const auto& [what, why] : m.refused) items.push_back(what + ": " + why);
  return items.empty() ? "" : "Not run:\n\n" + bullet_list(items) + "\n";
}

std::string landing_table(const Measurement& m) {
  std::vector<std::vector<std::string>> rows;
  for (const LandingRow& r : landing_rows(m)) {
    const bool ran = std::isfinite(r.ns);
    const bool tumble = r.engine == "tumble";
    std::string asleep = "n/a", all = r.sleeps ? "n/a" : "no sleeping";
    if (std::isfinite(r.asleep_fraction)) asleep = fixed(100.0 * r.asleep_fraction, 0) + " %";
    if (std::isfinite(r.all_asleep_at)) all = fmt(r.all_asleep_at) + " s";
    else if (r.sleeps && std::isfinite(r.watched_until)) all = "> " + fmt(r.watched_until) + " s";
    rows.push_back({std::to_string(r.n), r.engine, ran ? fmt(r.ns) : "did not run",
                    tumble ? "1" : (ran ? fmt(r.ratio) + "×" : "–"), ran ? fmt(r.ns_head) : "–",
                    tumble ? "1" : (ran ? fmt(r.ratio_head) + "×" : "–"),
                    fmt(r.impacts_per_box), asleep, all});
  }
  return md_table({"N", "engine", "ns per body-step", "ratio", "ns per body-step, first part",
                   "ratio, first part", "impacts per box", "asleep at the end", "all asleep at"},
                  rows);
}

std::string landing_notes(const Measurement& m) {
  std::vector<std::string> items;
  for (const LandingRow& r : landing_rows(m))
    if (!r.trouble.empty())
      items.push_back("landing N = " + std::to_string(r.n) + " on " + r.engine + ": " + r.trouble);
  return items.empty() ? "" : "\nNot run or not valid:\n\n" + bullet_list(items);
}

}  // namespace

void report(const Options& o, const Measurement& m, const Files& files) {
  const double e = m.bounce_e, h0 = m.bounce_h0;
  const Fields f{
      {"settings", settings()},
      {"tumble_plot", image_link(o, files.tumble_svg, "tumble: peers work-precision")},
      {"tumble_table", tumble_table(m)},
      {"finest_dt", o.quick ? "1/120" : "1/3840"},
      {"tumble_csv", file_link(o, files.tumble_csv)},
      {"h0", fmt(h0)},
      {"e", fmt(e)},
      {"apexes", fmt(e * e * h0, 6) + ", " + fmt(std::pow(e, 4) * h0, 6) + ", " +
                     fmt(std::pow(e, 6) * h0, 6)},
      {"bounce_csv", file_link(o, files.bounce_csv)},
      {"bounce_table", bounce_table(m)},
      {"duration", fmt(m.duration)},
      {"resting", std::to_string(m.resting)},
      {"skip_steps", std::to_string(m.skip_steps)},
      {"reps", std::to_string(m.reps)},
      {"throughput_csv", file_link(o, files.throughput_csv)},
      {"throughput_plot", image_link(o, files.throughput_svg, "throughput on every engine")},
      {"n_small", std::to_string(m.sizes.front())},
      {"n_large", std::to_string(m.sizes.back())},
      {"throughput_table", throughput_table(m)},
      {"skip_table", skip_table(m)},
      {"not_run", not_run(m)},
      {"landing_duration", fmt(static_cast<double>(m.landing_plan.steps) / 240.0)},
      {"landing_head", fmt(static_cast<double>(m.landing_plan.head_steps) / 240.0)},
      {"landing_watched", fmt(landing::watched_until(m.landing_plan, 1.0 / 240.0))},
      {"landing_csv", file_link(o, files.landing_csv)},
      {"landing_table", landing_table(m) + landing_notes(m)},
  };
  write_section(o, "peers", fill_template("peers", f));
}

}  // namespace tumble_bench::peers
