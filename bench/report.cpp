#include "report.hpp"
#include "text.hpp"

#include <cmath>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <sstream>

#include "tumble/scene.hpp"

namespace tumble_bench {
namespace {

std::string read_all(const fs::path& p) {
  std::ifstream f(p);
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

double number(const std::map<std::string, std::string>& v, const std::string& key) {
  const auto it = v.find(key);
  if (it == v.end()) return NAN;
  char* end = nullptr;
  const double d = std::strtod(it->second.c_str(), &end);
  return end == it->second.c_str() ? NAN : d;
}

std::string text(const std::map<std::string, std::string>& v, const std::string& key) {
  const auto it = v.find(key);
  return it == v.end() ? "not measured" : it->second;
}

std::string verdict(double value, double goal, bool lower_is_better = true) {
  if (std::isnan(value)) return "**not measured**";
  const bool met = lower_is_better ? value <= goal : value >= goal;
  return met ? "**met**" : "**not met**";
}

/// The landing, the large pyramid and the stage breakdown (issue 11's list), from the
/// values the `throughput`, `peers`, `contact`, `pile_precision` and `stages` sections
/// recorded.
std::string closing_note_contact(const std::map<std::string, std::string>& v) {
  std::ostringstream s;
  const std::string t = "throughput.landing.N10000.";
  s << "- **Landing, N = 10,000 unit cubes, μ = 1, e = 0** (`throughput` section): "
    << fmt(number(v, t + "ns_per_body_step")) << " ns per body-step over 2 s ("
    << fmt(number(v, t + "ns_per_body_step_first_0.5s")) << " ns over the first 0.5 s), "
    << fmt(number(v, t + "impacts_per_box")) << " impacts per box, "
    << fixed(100.0 * number(v, t + "asleep_fraction"), 0) << " % asleep at 2 s, ";
  const double all_asleep = number(v, t + "all_asleep_s");
  s << (std::isnan(all_asleep) ? "not all asleep by the end of the run."
                               : "all asleep at " + fmt(all_asleep) + " s.");
  const double bullet = number(v, "peers.landing.N10000.bullet.ratio_peer_over_tumble");
  s << " Bullet's time / Tumble's in the `peers` run: " << fmt(bullet)
    << "×, goal ≥ 2×: " << verdict(bullet, 2.0, false) << ".\n";
  const std::string p = "contact.pyramid_large.";
  s << "- **`pyramid_large`** (5,050 cubes, `contact` section): top box moved "
    << fmt(number(v, p + "tumble_top_moved_m")) << " m, stands (≤ 5 cm): "
    << text(v, p + "tumble_stands") << "; asleep at " << fmt(number(v, p + "tumble_asleep_s"))
    << " s; " << fmt(number(v, p + "tumble_ms")) << " ms per step awake, fastest peer "
    << text(v, p + "fastest_peer") << " at " << fmt(number(v, p + "ratio_to_fastest"))
    << "× Tumble's time.\n";
  const std::string pp = "pile_precision.";
  const auto within = [&](const std::string& engine) {  // "from dt = 1/480 (…)" or "at no dt"
    const std::string dt = text(v, pp + engine + ".dt_within_bound");
    if (dt == "none" || dt == "not measured") return std::string("at no dt measured");
    return "from dt = " + dt + " (" + fmt(number(v, pp + engine + ".cpu_within_bound")) +
           " CPU s per simulated s, against " + fmt(number(v, pp + engine + ".cpu_per_sim_s")) +
           " at 1/60)";
  };
  s << "- **`pile` within 1 cm at every step** (`pile_precision` section): at dt = 1/60 Tumble's "
       "deepest overlap is "
    << fmt(100.0 * number(v, pp + "tumble.deepest_m")) << " cm (Bullet "
    << fmt(100.0 * number(v, pp + "bullet.deepest_m")) << " cm); Tumble keeps 1 cm "
    << within("tumble") << ", Bullet " << within("bullet") << ". With the scene's overlap bound "
    << "at 1 cm (`max_overlap`, `tumble-bounded`) Tumble's deepest at dt = 1/60 is "
    << fmt(100.0 * number(v, pp + "tumble-bounded.deepest_m")) << " cm for "
    << fmt(number(v, pp + "tumble-bounded.cpu_per_sim_s")) << " CPU s per simulated s ("
    << fmt(number(v, pp + "tumble-bounded.cpu_per_sim_s") / number(v, pp + "tumble.cpu_per_sim_s"))
    << "× the plain run's). ";
  const double matched = number(v, pp + "bullet.cpu_ratio_at_tumble_depth");
  s << (std::isnan(matched) ? std::string("Bullet is deeper than Tumble's 1/60 overlap at every dt")
                            : "At Tumble's 1/60 overlap Bullet takes " + fmt(matched) +
                                  "× Tumble's CPU time (its curve interpolated)")
    << ".\n";
  s << "- **Per-stage breakdown** (`stages` section): "
    << (text(v, "stages.available") == "yes" ? "measured"
        : text(v, "stages.available") == "no"
            ? "stage timings not available in this engine build"
            : "not measured")
    << ".\n";
  return s.str();
}

/// Throughput of separated boxes at N = 10,000, alone and against the fastest peer.
std::string closing_note_throughput(const std::map<std::string, std::string>& v) {
  std::ostringstream s;
  s << "- **Throughput, N = 10,000** (`" << text(v, "throughput.integrator")
    << "`, `throughput` section, " << "goal ≤ 100 ns per body-step):\n";
  for (const char* shape : {"cube", "box"}) {
    const double ns = number(v, "throughput.ns_per_body_step.N10000." + std::string(shape));
    const std::string k = ".N10000." + std::string(shape);
    const double fall = number(v, "throughput.ns_per_body_step_fall" + k);
    s << "  - " << (std::string(shape) == "cube" ? "cubes" : "general boxes") << ": " << fmt(ns)
      << " ns per body-step over the whole scene (fall, impacts and resting on the floor; "
      << fixed(100.0 * number(v, "throughput.awake_fraction" + k), 0)
      << " % of the bodies awake on average, "
      << fmt(number(v, "throughput.ns_per_awake_body_step" + k))
      << " ns per awake body-step): " << verdict(ns, 100.0) << ". During the first 0.5 s "
      << "(the fall, before most impacts): " << fmt(fall) << " ns, " << verdict(fall, 100.0)
      << " for that phase alone.\n";
  }
  s << "- **Ratio to the fastest peer, N = 10,000** (one interleaved run of the `peers` "
       "section; goal ≥ 10×):\n";
  for (const char* shape : {"cube", "box"}) {
    const std::string k = std::string(".") + shape + ".N10000";
    const double ratio = number(v, "peers.ratio_to_fastest" + k);
    s << "  - " << (std::string(shape) == "cube" ? "cubes" : "general boxes") << ": Tumble "
      << fmt(number(v, "peers.tumble_ns" + k)) << " ns, fastest peer "
      << text(v, "peers.fastest" + k) << " at " << fmt(number(v, "peers.fastest_ns" + k))
      << " ns per body-step; peer time / Tumble time = " << fmt(ratio) << "×"
      << (ratio < 1.0 ? " (Tumble slower)" : "") << ": "
      << verdict(ratio, 10.0, false) << ".\n";
  }
  return s.str();
}

std::string closing_note(const Options& o, const std::map<std::string, std::string>& v) {
  std::ostringstream s;
  s << "## Closing note\n\n" << closing_note_throughput(v);
  const double skip = number(v, "skip.ms_per_step");
  const double awake1 = number(v, "skip.awake_after_step1");
  s << "- **Skip**: " << fmt(skip) << " ms per step for " << text(v, "skip.resting")
    << " resting + 10 falling boxes (" << fmt(number(v, "skip.ms_per_step_alone"))
    << " ms for the 10 alone), goal ≤ 0.2 ms: " << verdict(skip, 0.2)
    << ". First step " << fmt(number(v, "skip.first_step_ms")) << " ms ("
    << fmt(number(v, "skip.first_step_ms_alone")) << " ms alone) with " << fmt(awake1)
    << " bodies awake after it; cost following the awake bodies from the first step (only "
       "the 10 awake, and the first step itself within 0.2 ms): "
    << (std::isnan(awake1) ? "**not measured**"
        : awake1 <= 10.0 && number(v, "skip.first_step_ms") <= 0.2 ? "**met**"
                                                                      : "**not met**")
    << ".\n";
  s << "- **`tumble` orientation error at dt = 1/30** (geodesic angle after 20 s, rad):\n\n";
  std::vector<std::vector<std::string>> rows;
  for (tumble::Integrator i : tumble::kIntegrators) {
    const std::string n(tumble::to_string(i));
    rows.push_back({"Tumble `" + n + "`", fmt(number(v, "wp.tumble_err_dt30." + n))});
  }
  for (const auto& [key, value] : v) {
    if (key.rfind("peers.tumble_err_dt30.", 0) == 0) {
      rows.push_back({key.substr(22), fmt(number(v, key))});
    }
  }
  s << md_table({"engine / integrator", "error (rad)"}, rows) << '\n';
  const double exact = number(v, "wp.tumble_err_dt30.exact");
  s << "  Goal `exact` ≤ 1e-8 rad: " << verdict(exact, 1e-8) << ". The reference is known to "
    << text(v, "wp.tumble_reference_note") << ".\n";
  const double apex = number(v, "wp.bounce_apex1_err.exact.root");
  s << "- **First bounce apex** (`exact` + `root`, worst over every dt): " << fmt(apex)
    << " m, goal ≤ 1e-9 m: " << verdict(apex, 1e-9) << ".\n";
  s << closing_note_contact(v);
  const fs::path table = o.out / "stability_table.md";
  if (fs::exists(table)) {
    s << "- **Stability** (the table from the `stability` section):\n\n" << read_all(table)
      << '\n';
  }
  return s.str();
}

}  // namespace

void write_section(const Options& o, const std::string& name, const std::string& markdown) {
  std::ofstream(o.out / (name + ".md")) << markdown;
}

std::map<std::string, std::string> recorded_values(const Options& o) {
  std::map<std::string, std::string> v;
  std::ifstream f(o.out / "summary.csv");
  std::string line;
  std::getline(f, line);  // header
  while (std::getline(f, line)) {
    const auto comma = line.find(',');
    if (comma != std::string::npos) v[line.substr(0, comma)] = line.substr(comma + 1);
  }
  return v;
}

void record_value(const Options& o, const std::string& key, const std::string& value) {
  auto v = recorded_values(o);
  v[key] = value;
  std::ofstream f(o.out / "summary.csv");
  f << "key,value\n";
  for (const auto& [k, val] : v) f << k << ',' << val << '\n';
}

std::string image_link(const Options& o, const fs::path& svg, const std::string& alt) {
  const fs::path rel = fs::relative(fs::absolute(svg), fs::absolute(o.docs).parent_path());
  return "![" + alt + "](" + rel.generic_string() + ")";
}

std::string file_link(const Options& o, const fs::path& file) {
  const fs::path rel = fs::relative(fs::absolute(file), fs::absolute(o.docs).parent_path());
  return "[`" + file.filename().string() + "`](" + rel.generic_string() + ")";
}

void assemble_docs(const Options& o, const std::string& command_line) {
  const auto v = recorded_values(o);
  std::ostringstream d;
  d << "# Benchmarks\n\n"
    << "<!-- Generated by tumble-bench; edit the prose in bench/text/*.md and the code in "
       "bench/, not this file. -->\n\n"
    << "Everything on this page (tables, plots, numbers) was produced by one command:\n\n"
    << "```sh\n" << command_line << "\n```\n\n"
    << "Machine: " << text(v, "machine") << ". Engine at commit "
    << text(v, "engine_commit") << ". Run on " << text(v, "date")
    << (o.quick ? " with `--quick` (short sweeps; numbers are indicative only)" : "")
    << ". The machine is shared and noisy: timings are CPU time of the benchmark thread, "
       "ratios come from one run with the engines interleaved. Raw results are CSV files "
       "next to the plots in "
    << file_link(o, o.out) << "; see [bench/README.md](../bench/README.md) to reproduce.\n\n";
  for (const char* name : kSections) {
    const fs::path p = o.out / (std::string(name) + ".md");
    if (fs::exists(p)) d << read_all(p) << '\n';
  }
  d << closing_note(o, v);
  // The server's own measurements (server_stream, server_load, server_worlds: not tumble-bench
  // programs), kept by hand in bench/text/server.md and placed after the engine's.
  d << '\n' << fill_template("server", {});
  fs::create_directories(fs::absolute(o.docs).parent_path());
  std::ofstream(o.docs) << d.str();
}

}  // namespace tumble_bench
