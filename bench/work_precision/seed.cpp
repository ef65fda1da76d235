/// work-precision on `seed`: the tumbling box on an elastic floor against an event-located
/// reference.
#include "report.hpp"
#include "scenes.hpp"
#include "text.hpp"
#include "tumble/world.hpp"
#include "work_precision/work_precision.hpp"

namespace tumble_bench::wp {
namespace {

constexpr double kEnd = 2.5;  // s

SeedRun run_seed(const tumble::Scene& s, const SeedReference& r, double E0, bool quick) {
  SeedRun run{combo_name(s.world.integrator, s.world.toi), s.world.dt,
              std::lround(kEnd / s.world.dt)};
  tumble::World w(s);
  for (long i = 0; i < run.steps; ++i) w.step();
  const tumble::Body& b = w.body(0);
  run.dx = (b.s.x - r.x).norm();
  run.da = tumble::rotation_angle_between(r.R, b.s.R);
  run.de = std::fabs(tumble::total_energy(b.s, b.c, s.world.gravity) - E0) / std::fabs(E0);
  run.impacts = static_cast<long long>(w.total_impacts());
  run.cpu = time_run(s, run.steps, quick ? 0.002 : 0.03);
  return run;
}

}  // namespace

SeedMeasurement measure_seed(const Options& o, Progress& bar) {
  const tumble::Scene base = bundled("seed");
  const tumble::World probe(base);
  const tumble::Body& b0 = probe.body(0);
  const tumble::Vec3 gravity = base.world.gravity;
  SeedMeasurement m;
  m.e = base.world.floor->restitution;
  m.t_end = kEnd;
  const SeedReference r1 = seed_reference(b0, gravity, m.e, kEnd, 1e-13);
  const SeedReference r2 = seed_reference(b0, gravity, m.e, kEnd, 5e-14);
  m.ref_impacts = r1.impacts;
  m.ref_dx = (r1.x - r2.x).norm();
  m.ref_da = tumble::rotation_angle_between(r1.R, r2.R);
  const double E0 = tumble::total_energy(b0.s, b0.c, gravity);
  for (tumble::Integrator integ : tumble::kIntegrators) {
    for (tumble::ToiMethod toi : kToiMethods) {
      for (double dt : step_sizes(o.quick)) {
        bar.note("seed " + combo_name(integ, toi) + " " + dt_label(dt));
        m.runs.push_back(run_seed(with(base, integ, toi, dt), r1, E0, o.quick));
        bar.tick();
      }
    }
  }
  return m;
}

Plots record_seed(const Options& o, const SeedMeasurement& m) {
  Plots p{o.out / "wp_seed.csv", {}};
  {
    Csv out(p.csv, {"method", "dt", "steps", "cpu_s", "position_err_m", "angle_err_rad",
                    "energy_rel_drift", "impacts"});
    for (const SeedRun& r : m.runs)
      out.row() << r.method << r.dt << r.steps << r.cpu << r.dx << r.da << r.de << r.impacts;
  }
  const std::string x = "CPU time per run (s)";
  p.svg.push_back(plot(o, "wp_seed_position",
                       log_plot("wp_seed.csv", x, "final position error (m)", 4, 5,
                                combo_names(), 1,
                                "seed (e = 1): final position error vs CPU time")));
  p.svg.push_back(plot(o, "wp_seed_energy",
                       log_plot("wp_seed.csv", x, "relative energy drift at the end", 4, 7,
                                combo_names(), 1, "seed (e = 1): energy drift vs CPU time")));
  return p;
}

std::string report_seed(const Options& o, const SeedMeasurement& m, const Plots& p) {
  std::vector<std::vector<std::string>> rows;
  for (const SeedRun& r : m.runs)
    if (std::fabs(r.dt - 1.0 / 30.0) < 1e-12)
      rows.push_back({"`" + r.method + "`", fmt(r.dx), fmt(r.da), fmt(r.de),
                      std::to_string(r.impacts), fmt(r.cpu * 1e6)});
  const Fields f{
      {"e", fmt(m.e)},
      {"t_end", fmt(m.t_end)},
      {"ref_impacts", std::to_string(m.ref_impacts)},
      {"ref_dx", fmt(m.ref_dx)},
      {"ref_da", fmt(m.ref_da)},
      {"csv", file_link(o, p.csv)},
      {"plot_position", image_link(o, p.svg[0], "seed final position error vs CPU time")},
      {"plot_energy", image_link(o, p.svg[1], "seed energy drift vs CPU time")},
      {"table", md_table({"integrator + TOI", "position error (m)", "angle error (rad)",
                          "energy drift (rel.)", "impacts", "CPU µs per run"},
                         rows)},
  };
  return fill_template("work_precision_seed", f);
}

}  // namespace tumble_bench::wp
