/// work-precision on `bounce`: apexes and impact times against the analytic bounces.
#include <algorithm>

#include "report.hpp"
#include "scenes.hpp"
#include "text.hpp"
#include "tumble/world.hpp"
#include "work_precision/work_precision.hpp"

namespace tumble_bench::wp {
namespace {

double lowest_y(const tumble::BodyState& s, const tumble::BodyConstants& c) {
  return s.x.y() - s.R.row(1).cwiseAbs().dot(c.half_extents);
}

/// Impact k at t_k, apex k = e^{2k} h0 at t_k + e^k v1 / g.
BounceAnalytic analytic(const tumble::Scene& base) {
  const tumble::World probe(base);
  const tumble::Body& b0 = probe.body(0);
  BounceAnalytic a;
  a.g = -base.world.gravity.y();
  a.e = base.world.floor->restitution;
  a.h0 = lowest_y(b0.s, b0.c) - base.world.floor->height;
  a.toi_tolerance = base.world.toi_tolerance;
  const double v1 = std::sqrt(2.0 * a.g * a.h0);
  double t = std::sqrt(2.0 * a.h0 / a.g);
  for (int k = 0; k < 3; ++k) {
    a.t_impact[k] = t;
    a.apex[k] = std::pow(a.e, 2.0 * (k + 1)) * a.h0;
    t += 2.0 * std::pow(a.e, k + 1) * v1 / a.g;
  }
  a.t_end = a.t_impact[2] + std::pow(a.e, 3) * v1 / a.g + 0.05;
  return a;
}

/// Steps `w` to the end, returning the first three apexes and impact times it implies.
void observe(tumble::World& w, long steps, double g, double floor_y,
             std::array<double, 3>& got_apex, std::array<double, 3>& got_t) {
  got_apex = got_t = {NAN, NAN, NAN};
  int impacts = 0, apexes = 0;
  double prev_vy = 0.0, prev_apex = 0.0;
  for (long i = 0; i < steps; ++i) {
    w.step();
    const tumble::Body& b = w.body(0);
    const double y = lowest_y(b.s, b.c) - floor_y;
    const double vy = b.s.P.y() * b.c.inv_mass;
    if (w.last_step().impacts > 0 && impacts < 3) {
      // Impact time implied by the post-step state: back along its parabola to y = 0.
      got_t[impacts++] = w.time() + (vy - std::sqrt(vy * vy + 2.0 * g * y)) / g;
    } else if (apexes < impacts && prev_vy > 0.0 && vy <= 0.0) {
      // Apex implied by the last state still rising (exact for a ballistic state).
      got_apex[apexes++] = prev_apex;
    }
    prev_vy = vy;
    prev_apex = y + vy * vy / (2.0 * g);
  }
}

BounceRun run_bounce(const tumble::Scene& s, const BounceAnalytic& a, bool quick) {
  BounceRun r{combo_name(s.world.integrator, s.world.toi), s.world.dt,
              std::lround(std::ceil(a.t_end / s.world.dt))};
  tumble::World w(s);
  std::array<double, 3> got_t;
  observe(w, r.steps, a.g, s.world.floor->height, r.apex, got_t);
  auto err = [](double got, double want) { return std::isnan(got) ? INFINITY : std::fabs(got - want); };
  r.apex_err = r.t_err = 0.0;
  for (int k = 0; k < 3; ++k) {
    r.apex_err = std::max(r.apex_err, err(r.apex[k], a.apex[k]));
    r.t_err = std::max(r.t_err, err(got_t[k], a.t_impact[k]));
  }
  r.apex1_err = err(r.apex[0], a.apex[0]);
  r.cpu = time_run(s, r.steps, quick ? 0.002 : 0.03);
  return r;
}

}  // namespace

BounceMeasurement measure_bounce(const Options& o, Progress& bar) {
  const tumble::Scene base = bundled("bounce");
  BounceMeasurement m;
  m.a = analytic(base);
  for (tumble::Integrator integ : tumble::kIntegrators) {
    for (tumble::ToiMethod toi : kToiMethods) {
      for (double dt : step_sizes(o.quick)) {
        bar.note("bounce " + combo_name(integ, toi) + " " + dt_label(dt));
        m.runs.push_back(run_bounce(with(base, integ, toi, dt), m.a, o.quick));
        if (integ == tumble::Integrator::exact && toi == tumble::ToiMethod::root)
          m.worst_apex1_exact_root = std::max(m.worst_apex1_exact_root, m.runs.back().apex1_err);
        bar.tick();
      }
    }
  }
  return m;
}

Plots record_bounce(const Options& o, const BounceMeasurement& m) {
  Plots p{o.out / "wp_bounce.csv", {}};
  {
    Csv out(p.csv, {"method", "dt", "steps", "cpu_s", "apex_err_m", "impact_time_err_s",
                    "apex1_err_m", "apex1_m", "apex2_m", "apex3_m"});
    for (const BounceRun& r : m.runs)
      out.row() << r.method << r.dt << r.steps << r.cpu << r.apex_err << r.t_err << r.apex1_err
                << r.apex[0] << r.apex[1] << r.apex[2];
  }
  record_value(o, "wp.bounce_apex1_err.exact.root", fmt(m.worst_apex1_exact_root, 4));
  const std::string x = "CPU time per run (s)";
  p.svg.push_back(plot(o, "wp_bounce_apex",
                       log_plot("wp_bounce.csv", x, "worst error of the first three apexes (m)",
                                4, 5, combo_names(), 1, "bounce: apex error vs CPU time")));
  p.svg.push_back(plot(o, "wp_bounce_time",
                       log_plot("wp_bounce.csv", x, "worst impact-time error (s)", 4, 6,
                                combo_names(), 1, "bounce: impact-time error vs CPU time")));
  return p;
}

std::string report_bounce(const Options& o, const BounceMeasurement& m, const Plots& p) {
  std::vector<std::vector<std::string>> rows;
  for (const BounceRun& r : m.runs)
    if (std::fabs(r.dt - 1.0 / 60.0) < 1e-12)
      rows.push_back({"`" + r.method + "`", fmt(r.apex1_err), fmt(r.apex_err), fmt(r.t_err),
                      fmt(r.cpu * 1e6)});
  const BounceAnalytic& a = m.a;
  const Fields f{
      {"h0", fmt(a.h0)},
      {"e", fmt(a.e)},
      {"g", fmt(a.g)},
      {"toi_tolerance", fmt(a.toi_tolerance)},
      {"apexes", fmt(a.apex[0], 6) + ", " + fmt(a.apex[1], 6) + ", " + fmt(a.apex[2], 6)},
      {"impacts", fmt(a.t_impact[0], 8) + ", " + fmt(a.t_impact[1], 8) + ", " +
                      fmt(a.t_impact[2], 8)},
      {"csv", file_link(o, p.csv)},
      {"plot_apex", image_link(o, p.svg[0], "bounce apex error vs CPU time")},
      {"plot_time", image_link(o, p.svg[1], "bounce impact-time error vs CPU time")},
      {"table", md_table({"integrator + TOI", "apex 1 error (m)", "worst apex error (m)",
                          "worst impact-time error (s)", "CPU µs per run"},
                         rows)},
      {"worst_apex1", fmt(m.worst_apex1_exact_root)},
  };
  return fill_template("work_precision_bounce", f);
}

}  // namespace tumble_bench::wp
