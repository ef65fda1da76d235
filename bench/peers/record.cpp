/// peers, record: peers_tumble.csv, peers_bounce.csv, peers_throughput.csv, peers_landing.csv,
/// the headline values and the two plots.
#include <cmath>
#include <iostream>
#include <sstream>

#include "peers/peers.hpp"
#include "report.hpp"

namespace tumble_bench::peers {
namespace {

std::string tumble_plot(const Measurement& m) {
  std::ostringstream g;
  g << "set logscale xy\nset format y '10^{%L}'\nset format x '10^{%L}'\n"
    << "set title 'tumble on every engine: orientation error at 20 s vs CPU time'\n"
    << "set xlabel 'CPU time per run (s)'\nset ylabel 'orientation error (rad)'\nplot ";
  for (std::size_t i = 0; i < m.all.size(); ++i)
    g << (i ? ", \\\n     " : "") << "'peers_tumble.csv' skip 1 using (strcol(1) eq '"
      << m.all[i].name << "' ? $3 : 1/0):(($4 > 1e-17) ? $4 : 1e-17) with linespoints lw 1.5 "
      << "title '" << m.all[i].name << "'";
  return g.str();
}

std::string throughput_plot(const Measurement& m) {
  std::ostringstream g;
  g << "set logscale xy\nset title 'throughput on every engine (dt = 1/240 s)'\n"
    << "set xlabel 'bodies N'\nset ylabel 'CPU ns per body-step'\nset xrange [500:20000]\n"
    << "plot ";
  bool first = true;
  for (const Contender& c : m.fast) {
    for (BoxShape shape : {BoxShape::cube, BoxShape::general}) {
      const std::string sn = to_string(shape);
      g << (first ? "" : ", \\\n     ") << "'peers_throughput.csv' skip 1 using "
        << "(strcol(1) eq '" << c.name << "' && strcol(2) eq '" << sn
        << "' ? $3 : 1/0):4 with linespoints lw 2 " << (shape == BoxShape::cube ? "dt 2 " : "")
        << "title '" << c.name << ", " << (shape == BoxShape::cube ? "cubes" : "boxes") << "'";
      first = false;
    }
  }
  return g.str();
}

void record_tumble(const Options& o, const Measurement& m, const fs::path& csv) {
  Csv out(csv, {"engine", "dt", "cpu_s", "angle_err_rad"});
  for (const TumbleRun& r : m.tumble) {
    out.row() << r.engine << r.dt << r.cpu << r.err;
    if (r.engine != "tumble" && std::fabs(r.dt - 1.0 / 30.0) < 1e-12)
      record_value(o, "peers.tumble_err_dt30." + r.engine, fmt(r.err, 4));
  }
}

void record_bounce(const Measurement& m, const fs::path& csv) {
  Csv out(csv, {"engine", "dt", "apex1_m", "apex2_m", "apex3_m", "apex1_err_m"});
  for (const BounceRun& r : m.bounce)
    out.row() << r.engine << 1.0 / 60.0 << r.apex[0] << r.apex[1] << r.apex[2] << r.err;
}

/// One (N, shape): every peer's row, then Tumble's; the headline values at the largest N.
void record_throughput_key(const Options& o, const Measurement& m, const Key& key, Csv& out) {
  const auto [n, shape] = key;
  const std::string shape_name = to_string(shape);
  const double tumble_ns = median(m.ns.at("tumble").at(key));
  std::string fastest = "none";
  double fastest_ns = NAN;
  for (const Contender& c : m.fast) {
    if (c.name == "tumble") continue;
    const double v = median(m.ns.at(c.name).at(key));
    out.row() << c.name << shape_name << n << v << v / tumble_ns;
    if (std::isfinite(v) && !(v >= fastest_ns)) {
      fastest_ns = v;
      fastest = c.name;
    }
    std::cerr << "  N = " << n << " " << shape_name << ": " << c.name << " " << fmt(v)
              << " ns/body-step, Tumble is " << fmt(v / tumble_ns) << "x faster\n";
  }
  out.row() << "tumble" << shape_name << n << tumble_ns << 1.0;
  if (n != m.sizes.back()) return;
  const std::string k = "." + shape_name + ".N10000";
  record_value(o, "peers.fastest" + k, fastest);
  record_value(o, "peers.fastest_ns" + k, fmt(fastest_ns, 4));
  record_value(o, "peers.ratio_to_fastest" + k, fmt(fastest_ns / tumble_ns, 4));
  record_value(o, "peers.tumble_ns" + k, fmt(tumble_ns, 4));
}

void record_skip(const Options& o, const Measurement& m) {
  const double tumble_skip = median(m.skip_ms.at("tumble"));
  for (const Contender& c : m.fast) {
    if (c.name == "tumble") continue;
    const double v = median(m.skip_ms.at(c.name));
    std::cerr << "  skip: " << c.name << " " << fmt(v) << " ms/step, Tumble is "
              << fmt(v / tumble_skip) << "x faster\n";
    record_value(o, "peers.skip_ms." + c.name, fmt(v, 4));
  }
}

void record_landing(const Options& o, const Measurement& m, const fs::path& csv) {
  Csv out(csv, {"engine", "n", "steps", "ns_per_body_step", "ns_per_body_step_first_0.5s",
                "ratio_peer_over_tumble", "ratio_peer_over_tumble_first_0.5s",
                "impacts_per_box", "asleep_fraction_end", "all_asleep_at_s", "watched_until_s",
                "note"});
  for (const LandingRow& r : landing_rows(m)) {
    out.row() << r.engine << r.n << m.landing_plan.steps << r.ns << r.ns_head << r.ratio
              << r.ratio_head << r.impacts_per_box << r.asleep_fraction << r.all_asleep_at
              << r.watched_until << r.trouble;
    std::cerr << "  landing N = " << r.n << " " << r.engine << ": " << fmt(r.ns)
              << " ns/body-step (peer/Tumble " << fmt(r.ratio) << "), first part "
              << fmt(r.ns_head) << ", impacts/box " << fmt(r.impacts_per_box) << ", asleep "
              << fmt(r.asleep_fraction) << ", all asleep at " << fmt(r.all_asleep_at) << " s\n";
    // Headline values at N = 10,000 (with --quick: the largest N, under the same keys).
    if (r.n != 10000 && !(o.quick && r.n == m.landing_sizes.back())) continue;
    const std::string k = "peers.landing.N10000." + r.engine + ".";
    record_value(o, k + "ns_per_body_step", fmt(r.ns, 4));
    record_value(o, k + "ns_per_body_step_first_0.5s", fmt(r.ns_head, 4));
    if (r.engine != "tumble") record_value(o, k + "ratio_peer_over_tumble", fmt(r.ratio, 4));
  }
}

}  // namespace

Files record(const Options& o, const Measurement& m) {
  Files f;
  f.tumble_csv = o.out / "peers_tumble.csv";
  f.bounce_csv = o.out / "peers_bounce.csv";
  f.throughput_csv = o.out / "peers_throughput.csv";
  f.landing_csv = o.out / "peers_landing.csv";
  record_tumble(o, m, f.tumble_csv);
  f.tumble_svg = plot(o, "peers_tumble", tumble_plot(m));
  record_bounce(m, f.bounce_csv);
  {
    Csv out(f.throughput_csv, {"engine", "shape", "n", "ns_per_body_step",
                               "ratio_peer_over_tumble"});
    for (const auto& [key, runs] : m.ns.at("tumble")) record_throughput_key(o, m, key, out);
  }
  record_skip(o, m);
  record_landing(o, m, f.landing_csv);
  f.throughput_svg = plot(o, "peers_throughput", throughput_plot(m));
  return f;
}

}  // namespace tumble_bench::peers
