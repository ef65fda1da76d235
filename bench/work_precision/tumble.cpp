/// work-precision on `tumble`: the tennis-racket flip against an odeint reference.
#include <algorithm>

#include "report.hpp"
#include "scenes.hpp"
#include "text.hpp"
#include "tumble/world.hpp"
#include "tumble_reference/free_rigid_body.hpp"
#include "work_precision/work_precision.hpp"

namespace tumble_bench::wp {
namespace {

namespace ref = tumble_reference;
constexpr double kDuration = 20.0;  // s

/// One run of `s` for 20 s: the errors at the end, the largest energy error on the way.
TumbleRun run_tumble(const tumble::Scene& s, const tumble::Mat3& R_ref, bool quick) {
  TumbleRun r{std::string(tumble::to_string(s.world.integrator)), s.world.dt,
              std::lround(kDuration / s.world.dt)};
  tumble::World w(s);
  const tumble::Body& b = w.body(0);
  const double E0 = tumble::kinetic_energy(b.s, b.c);
  const double L0 = b.s.L.norm();
  r.e_max = 0.0;
  for (long i = 0; i < r.steps; ++i) {
    w.step();
    r.e_max = std::max(r.e_max, std::fabs(tumble::kinetic_energy(b.s, b.c) - E0) / E0);
  }
  r.angle = tumble::rotation_angle_between(R_ref, b.s.R);
  r.e_rel = std::fabs(tumble::kinetic_energy(b.s, b.c) - E0) / E0;
  r.l_rel = std::fabs(b.s.L.norm() - L0) / L0;
  r.cpu = time_run(s, r.steps, quick ? 0.002 : 0.05);
  return r;
}

}  // namespace

TumbleMeasurement measure_tumble(const Options& o, Progress& bar) {
  const tumble::Scene base = bundled("tumble");
  const tumble::World probe(base);
  const tumble::Body& b0 = probe.body(0);
  const tumble::Vec3 I = b0.c.inertia;
  // Reference: RKF78 at 1e-13, checked against halving the tolerance and against an
  // independent long-double Bulirsch–Stoer solve of the matrix equation.
  const tumble::Mat3 R_ref = ref::free_rigid_body_attitude(I, b0.s.R, b0.s.L, kDuration);
  const tumble::Mat3 R_half = ref::free_rigid_body_attitude(
      I, b0.s.R, b0.s.L, kDuration, ref::Method::kQuaternionRkf78, 5e-14);
  const tumble::Mat3 R_bs = ref::free_rigid_body_attitude(I, b0.s.R, b0.s.L, kDuration,
                                                          ref::Method::kMatrixBulirschStoer);
  TumbleMeasurement m;
  m.ref_half = tumble::rotation_angle_between(R_ref, R_half);
  m.ref_bs = tumble::rotation_angle_between(R_ref, R_bs);
  for (tumble::Integrator integ : tumble::kIntegrators) {
    for (double dt : step_sizes(o.quick)) {
      bar.note("tumble " + std::string(tumble::to_string(integ)) + " " + dt_label(dt));
      m.runs.push_back(run_tumble(with(base, integ, tumble::ToiMethod::root, dt), R_ref, o.quick));
      bar.tick();
    }
  }
  return m;
}

Plots record_tumble(const Options& o, const TumbleMeasurement& m) {
  Plots p{o.out / "wp_tumble.csv", {}};
  {
    Csv out(p.csv, {"integrator", "dt", "steps", "cpu_s", "angle_err_rad", "energy_rel_err",
                    "L_rel_err", "energy_rel_err_max"});
    for (const TumbleRun& r : m.runs) {
      out.row() << r.integrator << r.dt << r.steps << r.cpu << r.angle << r.e_rel << r.l_rel
                << r.e_max;
      if (std::fabs(r.dt - 1.0 / 30.0) < 1e-12)
        record_value(o, "wp.tumble_err_dt30." + r.integrator, fmt(r.angle, 4));
    }
  }
  record_value(o, "wp.tumble_reference_note",
               "about " + fmt(std::max(m.ref_half, m.ref_bs), 2) +
                   " rad (RKF78 at tol 1e-13 vs 5e-14: " + fmt(m.ref_half, 2) +
                   " rad; vs long-double Bulirsch–Stoer at 1e-17: " + fmt(m.ref_bs, 2) + " rad)");
  std::vector<std::string> names;
  for (tumble::Integrator i : tumble::kIntegrators) names.emplace_back(tumble::to_string(i));
  const std::string x = "CPU time per run (s)";
  p.svg.push_back(plot(o, "wp_tumble_angle",
                       log_plot("wp_tumble.csv", x, "orientation error at 20 s (rad)", 4, 5,
                                names, 1, "tumble: geodesic orientation error vs CPU time")));
  p.svg.push_back(plot(o, "wp_tumble_energy",
                       log_plot("wp_tumble.csv", x, "max relative energy error", 4, 8, names, 1,
                                "tumble: energy error vs CPU time")));
  p.svg.push_back(plot(o, "wp_tumble_L",
                       log_plot("wp_tumble.csv", x, "relative |L| error at 20 s", 4, 7, names,
                                1, "tumble: |L| error vs CPU time")));
  return p;
}

std::string report_tumble(const Options& o, const TumbleMeasurement& m, const Plots& p) {
  std::vector<std::vector<std::string>> rows;
  for (const TumbleRun& r : m.runs)
    if (std::fabs(r.dt - 1.0 / 30.0) < 1e-12)
      rows.push_back({"`" + r.integrator + "`", fmt(r.angle), fmt(r.e_rel), fmt(r.l_rel),
                      fmt(r.cpu * 1e3)});
  const Fields f{
      {"finest_dt", dt_label(step_sizes(o.quick).back())},
      {"reference_note", recorded_values(o)["wp.tumble_reference_note"]},
      {"csv", file_link(o, p.csv)},
      {"plot_angle", image_link(o, p.svg[0], "tumble orientation error vs CPU time")},
      {"plot_energy", image_link(o, p.svg[1], "tumble energy error vs CPU time")},
      {"plot_L", image_link(o, p.svg[2], "tumble |L| error vs CPU time")},
      {"table", md_table({"integrator", "angle error (rad)", "energy rel. error",
                          "‖L‖ rel. error", "CPU ms per 20 s run"},
                         rows)},
  };
  return fill_template("work_precision_tumble", f);
}

}  // namespace tumble_bench::wp
