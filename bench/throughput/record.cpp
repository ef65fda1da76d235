/// throughput, record: throughput.csv, throughput_landing.csv, headline values, the plot.
#include <cmath>
#include <iostream>
#include <sstream>

#include "report.hpp"
#include "throughput/throughput.hpp"

namespace tumble_bench::throughput {
namespace {

void record_scaling(const Options& o, const Measurement& m, Csv& out) {
  for (const ScalingRow& r : scaling_rows(m)) {
    const std::string shape = to_string(r.shape);
    out.row() << shape << "exact" << r.n << r.steps << r.runs << r.ns << r.ns_head << r.ns_awake
              << r.last.awake_fraction << r.last.peak_mb << r.last.bytes_per_body;
    if (r.n == 10000 || (o.quick && r.n == m.cfg.sizes.back())) {
      record_value(o, "throughput.ns_per_body_step.N10000." + shape, fmt(r.ns, 4));
      record_value(o, "throughput.ns_per_awake_body_step.N10000." + shape, fmt(r.ns_awake, 4));
      record_value(o, "throughput.ns_per_body_step_fall.N10000." + shape, fmt(r.ns_head, 4));
      record_value(o, "throughput.awake_fraction.N10000." + shape,
                   fmt(r.last.awake_fraction, 4));
    }
  }
}

void record_integrators(const Options& o, const Measurement& m, Csv& out) {
  for (tumble::Integrator integ : tumble::kIntegrators) {
    for (BoxShape shape : kShapes) {
      const std::vector<double>& v = m.by_integrator.at({shape, integ});
      const double med = median(v);
      const std::string name(tumble::to_string(integ));
      out.row() << to_string(shape) << name << m.cfg.n_integ << m.cfg.steps << v.size() << med
                << NAN << NAN << NAN << NAN << NAN;
      if (!o.quick)
        record_value(o, "throughput.ns_by_integrator." + std::string(to_string(shape)) + "." +
                            name, fmt(med, 4));
    }
  }
}

void record_landing(const Options& o, const Measurement& m, const fs::path& path) {
  Csv out(path, {"n", "steps", "runs", "ns_per_body_step", "ns_per_body_step_first_0.5s",
                 "impacts_per_box", "asleep_fraction_end", "all_asleep_at_s",
                 "watched_until_s", "note"});
  for (const LandingRow& r : landing_rows(m)) {
    out.row() << r.n << m.cfg.landing.steps << r.runs << r.ns << r.ns_head << r.impacts_per_box
              << r.asleep_fraction << r.all_asleep_at << r.watched_until << r.trouble;
    std::cerr << "  landing N = " << r.n << ": " << fmt(r.ns) << " ns/body-step (first part "
              << fmt(r.ns_head) << "), " << fmt(r.impacts_per_box) << " impacts per box, "
              << fixed(100.0 * r.asleep_fraction, 0) << " % asleep at the end, all asleep at "
              << fmt(r.all_asleep_at) << " s\n";
    // Headline values at N = 10,000 (with --quick: the largest N, under the same keys).
    if (r.n != 10000 && !(o.quick && r.n == m.cfg.landing_sizes.back())) continue;
    const std::string k = "throughput.landing.N10000.";
    record_value(o, k + "ns_per_body_step", fmt(r.ns, 4));
    record_value(o, k + "ns_per_body_step_first_0.5s", fmt(r.ns_head, 4));
    record_value(o, k + "impacts_per_box", fmt(r.impacts_per_box, 4));
    record_value(o, k + "asleep_fraction", fmt(r.asleep_fraction, 4));
    record_value(o, k + "all_asleep_s", fmt(r.all_asleep_at, 4));
  }
}

std::string plot_script(const Measurement& m) {
  const double d = m.cfg.duration;
  std::ostringstream g;
  g << "set logscale x\nset logscale y\nset format x '10^{%L}'\n"
    << "set title 'throughput: N separated falling boxes, exact, dt = 1/240 s'\n"
    << "set xlabel 'bodies N'\nset ylabel 'CPU ns per body-step'\nset y2label 'peak RSS (MB)'\n"
    << "set y2tics\nset logscale y2\nset ytics nomirror\n"
    << "sel(s) = strcol(1) eq s && strcol(2) eq 'exact'\n"
    << "plot 'throughput.csv' skip 1 using (sel('box') ? $3 : 1/0):7 with linespoints lw 2 pt 7 "
       "title 'general boxes, first 0.5 s', \\\n"
    << "     'throughput.csv' skip 1 using (sel('box') ? $3 : 1/0):6 with linespoints lw 2 pt 5 "
       "title 'general boxes, " << d << " s', \\\n"
    << "     'throughput.csv' skip 1 using (sel('cube') ? $3 : 1/0):7 with linespoints lw 2 pt 6 "
       "title 'cubes, first 0.5 s', \\\n"
    << "     'throughput.csv' skip 1 using (sel('cube') ? $3 : 1/0):6 with linespoints lw 2 pt 4 "
       "title 'cubes, " << d << " s', \\\n"
    << "     'throughput.csv' skip 1 using (sel('box') ? $3 : 1/0):10 axes x1y2 with "
       "linespoints dt 2 lc rgb 'gray40' title 'peak RSS, boxes (MB)', \\\n"
    << "     100 with lines lc rgb 'gray' dt 3 title 'goal 100 ns'\n";
  return g.str();
}

}  // namespace

Files record(const Options& o, const Measurement& m) {
  Files f{o.out / "throughput.csv", o.out / "throughput_landing.csv", {}};
  {
    Csv out(f.csv, {"shape", "integrator", "n", "steps", "runs", "ns_per_body_step",
                    "ns_per_body_step_first_0.5s", "ns_per_awake_body_step", "awake_fraction",
                    "peak_rss_mb", "bytes_per_body"});
    record_scaling(o, m, out);
    record_integrators(o, m, out);
  }
  record_value(o, "throughput.integrator", "exact");
  record_landing(o, m, f.landing_csv);
  f.svg = plot(o, "throughput", plot_script(m));
  return f;
}

}  // namespace tumble_bench::throughput
