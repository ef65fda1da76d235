/// throughput, report: the `throughput` section, bench/text/throughput.md filled in.
#include <algorithm>
#include <cmath>

#include "report.hpp"
#include "text.hpp"
#include "throughput/throughput.hpp"

namespace tumble_bench::throughput {
namespace {

std::string scaling_table(const Measurement& m) {
  std::vector<std::vector<std::string>> rows;
  for (const ScalingRow& r : scaling_rows(m))
    rows.push_back({std::to_string(r.n), to_string(r.shape), r.full ? fmt(r.ns) : "—",
                    fmt(r.ns_head), r.full ? fmt(r.ns_awake) : "—",
                    fixed(100.0 * r.last.awake_fraction, 0) + " %", fmt(r.last.peak_mb),
                    fmt(r.last.bytes_per_body)});
  return md_table({"N", "shape", "ns per body-step",
                   "ns per body-step, first " + fmt(m.cfg.head_duration) + " s",
                   "ns per awake body-step", "awake", "peak RSS (MB)", "bytes per body"},
                  rows);
}

std::string integrator_table(const Measurement& m) {
  std::vector<std::vector<std::string>> rows;
  for (tumble::Integrator integ : tumble::kIntegrators) {
    std::vector<std::string> row{"`" + std::string(tumble::to_string(integ)) + "`"};
    for (BoxShape shape : kShapes) row.push_back(fmt(median(m.by_integrator.at({shape, integ}))));
    rows.push_back(row);
  }
  return md_table({"integrator", "cubes: ns per body-step", "general boxes: ns per body-step"},
                  rows);
}

/// "0.93 s", "> 4 s" or "n/a".
std::string asleep_at(double at, double watched) {
  if (std::isfinite(at)) return fmt(at) + " s";
  return std::isfinite(watched) ? "> " + fmt(watched) + " s" : "n/a";
}

std::string landing_table(const Measurement& m) {
  std::vector<std::vector<std::string>> rows;
  for (const LandingRow& r : landing_rows(m))
    rows.push_back({std::to_string(r.n), fmt(r.ns), fmt(r.ns_head), fmt(r.impacts_per_box),
                    std::isfinite(r.asleep_fraction)
                        ? fixed(100.0 * r.asleep_fraction, 0) + " %" : "n/a",
                    asleep_at(r.all_asleep_at, r.watched_until)});
  const std::string head = fmt(m.cfg.landing.head_steps * kDt);
  return md_table({"N", "ns per body-step", "ns per body-step, first " + head + " s",
                   "impacts per box", "asleep at the end", "all asleep at"},
                  rows);
}

std::string landing_notes(const Measurement& m) {
  std::vector<std::string> notes;
  for (const LandingRow& r : landing_rows(m))
    if (!r.trouble.empty()) notes.push_back("N = " + std::to_string(r.n) + ": " + r.trouble);
  return notes.empty() ? "" : "Trouble:\n\n" + bullet_list(notes);
}

std::string largest_full_n(const Config& c) {
  return std::to_string(*std::find_if(c.sizes.rbegin(), c.sizes.rend(),
                                      [&](std::size_t n) { return n < c.n_big; }));
}

}  // namespace

void report(const Options& o, const Measurement& m, const Files& files) {
  const Config& c = m.cfg;
  const bool big = std::any_of(c.sizes.begin(), c.sizes.end(),
                               [&](std::size_t n) { return n >= c.n_big; });
  const Fields f{
      {"duration", fmt(c.duration)},
      {"steps", std::to_string(c.steps)},
      {"largest_full_n", largest_full_n(c)},
      {"big_n_note", big ? "; N = 100,000 runs once for the first 0.5 s only (120 steps), "
                           "because the whole 2 s of general boxes would take over a minute of "
                           "CPU per run, so its only figure is the first-0.5-s column"
                         : ""},
      {"head_duration", fmt(c.head_duration)},
      {"csv", file_link(o, files.csv)},
      {"plot", image_link(o, files.svg, "throughput scaling")},
      {"scaling_table", scaling_table(m)},
      {"n_integ", std::to_string(c.n_integ)},
      {"reps", std::to_string(c.reps)},
      {"integrator_table", integrator_table(m)},
      {"landing_duration", fmt(static_cast<double>(c.landing.steps) * kDt)},
      {"landing_steps", std::to_string(c.landing.steps)},
      {"watched_until", fmt(landing::watched_until(c.landing, kDt))},
      {"landing_csv", file_link(o, files.landing_csv)},
      {"landing_table", landing_table(m)},
      {"landing_notes", landing_notes(m)},
  };
  write_section(o, "throughput", fill_template("throughput", f));
}

}  // namespace tumble_bench::throughput
