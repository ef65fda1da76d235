/// work-precision: error against CPU time, one curve per integrator (and TOI method).
/// Scenes: `tumble` (orientation, energy, |L| against an odeint reference), `bounce` (apexes
/// and impact times against the analytic values), `seed` with e = 1 (final state against an
/// event-located odeint reference, energy drift).
#include <boost/math/tools/toms748_solve.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "benchmarks.hpp"
#include "report.hpp"
#include "scenes.hpp"
#include "tumble/world.hpp"
#include "tumble_reference/free_rigid_body.hpp"

namespace tumble_bench {
namespace {

using tumble::Integrator;
using tumble::Mat3;
using tumble::ToiMethod;
using tumble::Vec3;
namespace ref = tumble_reference;

constexpr double kFloorForLog = 1e-17;  // errors of exactly 0 are drawn here on log axes

std::vector<double> step_sizes(bool quick) {
  std::vector<double> dts;
  const int n = quick ? 4 : 9;  // 1/15 … 1/3840 (quick: … 1/120)
  for (int k = 0; k < n; ++k) dts.push_back(1.0 / (15.0 * std::pow(2.0, k)));
  return dts;
}

/// CPU seconds of one run of `steps` steps (mean over as many repeats as fit in `budget`).
double time_run(const tumble::Scene& scene, long steps, double budget) {
  double total = 0.0;
  int reps = 0;
  do {
    tumble::World w(scene);
    const double t0 = thread_cpu_seconds();
    for (long i = 0; i < steps; ++i) w.step();
    total += thread_cpu_seconds() - t0;
    ++reps;
  } while (total < budget && reps < 50);
  return total / reps;
}

std::string log_plot(const std::string& csv, const std::string& xlabel, const std::string& ylabel,
                     int xcol, int ycol, const std::vector<std::string>& curves, int keycol,
                     const std::string& title) {
  std::ostringstream g;
  g << "set logscale xy\nset format y '10^{%L}'\nset format x '10^{%L}'\n"
    << "set title '" << title << "'\nset xlabel '" << xlabel << "'\nset ylabel '" << ylabel
    << "'\n"
    << "plot ";
  for (std::size_t i = 0; i < curves.size(); ++i) {
    g << (i ? ", \\\n     " : "") << "'" << csv << "' skip 1 using (strcol(" << keycol
      << ") eq '" << curves[i] << "' ? $" << xcol << " : 1/0):(max($" << ycol << ", "
      << kFloorForLog << ")) with linespoints lw 1.5 title '" << curves[i] << "'";
  }
  return "max(a,b) = a > b ? a : b\n" + g.str();
}

// ---------------------------------------------------------------- tumble

std::string work_precision_tumble(const Options& o, Progress& bar) {
  const tumble::Scene base = bundled("tumble");
  const double duration = 20.0;
  const tumble::World probe(base);
  const tumble::Body& b0 = probe.body(0);
  const Vec3 inertia = b0.c.inertia;
  const Mat3 R0 = b0.s.R;
  const Vec3 L0 = b0.s.L;
  const double E0 = tumble::kinetic_energy(b0.s, b0.c);

  // Reference: RKF78 at 1e-13, checked against halving the tolerance and against an
  // independent long-double Bulirsch–Stoer solve of the matrix equation.
  const Mat3 R_ref = ref::free_rigid_body_attitude(inertia, R0, L0, duration);
  const Mat3 R_half = ref::free_rigid_body_attitude(inertia, R0, L0, duration,
                                                    ref::Method::kQuaternionRkf78, 5e-14);
  const Mat3 R_bs = ref::free_rigid_body_attitude(inertia, R0, L0, duration,
                                                  ref::Method::kMatrixBulirschStoer);
  const double d_half = tumble::rotation_angle_between(R_ref, R_half);
  const double d_bs = tumble::rotation_angle_between(R_ref, R_bs);
  record_value(o, "wp.tumble_reference_note",
               "about " + fmt(std::max(d_half, d_bs), 2) +
                   " rad (RKF78 at tol 1e-13 vs 5e-14: " + fmt(d_half, 2) +
                   " rad; vs long-double Bulirsch–Stoer at 1e-17: " + fmt(d_bs, 2) + " rad)");

  const fs::path csv = o.out / "wp_tumble.csv";
  std::vector<std::vector<std::string>> rows;
  {
    Csv out(csv, {"integrator", "dt", "steps", "cpu_s", "angle_err_rad", "energy_rel_err",
                  "L_rel_err", "energy_rel_err_max"});
    for (Integrator integ : tumble::kIntegrators) {
      const std::string name(tumble::to_string(integ));
      for (double dt : step_sizes(o.quick)) {
        bar.note("tumble " + name + " " + dt_label(dt));
        const tumble::Scene s = with(base, integ, ToiMethod::root, dt);
        const long steps = std::lround(duration / dt);
        tumble::World w(s);
        double e_max = 0.0;
        for (long i = 0; i < steps; ++i) {
          w.step();
          const tumble::Body& b = w.body(0);
          e_max = std::max(e_max, std::fabs(tumble::kinetic_energy(b.s, b.c) - E0) / E0);
        }
        const tumble::Body& b = w.body(0);
        const double angle = tumble::rotation_angle_between(R_ref, b.s.R);
        const double e_rel = std::fabs(tumble::kinetic_energy(b.s, b.c) - E0) / E0;
        const double l_rel = std::fabs(b.s.L.norm() - L0.norm()) / L0.norm();
        const double cpu = time_run(s, steps, o.quick ? 0.002 : 0.05);
        out.row() << name << dt << steps << cpu << angle << e_rel << l_rel << e_max;
        if (std::fabs(dt - 1.0 / 30.0) < 1e-12) {
          record_value(o, "wp.tumble_err_dt30." + name, fmt(angle, 4));
          rows.push_back({"`" + name + "`", fmt(angle), fmt(e_rel), fmt(l_rel),
                          fmt(cpu * 1e3)});
        }
        bar.tick();
      }
    }
  }
  std::vector<std::string> names;
  for (Integrator i : tumble::kIntegrators) names.emplace_back(tumble::to_string(i));
  const fs::path p1 = plot(o, "wp_tumble_angle",
                           log_plot("wp_tumble.csv", "CPU time per run (s)",
                                    "orientation error at 20 s (rad)", 4, 5, names, 1,
                                    "tumble: geodesic orientation error vs CPU time"));
  const fs::path p2 = plot(o, "wp_tumble_energy",
                           log_plot("wp_tumble.csv", "CPU time per run (s)",
                                    "max relative energy error", 4, 8, names, 1,
                                    "tumble: energy error vs CPU time"));
  const fs::path p3 = plot(o, "wp_tumble_L",
                           log_plot("wp_tumble.csv", "CPU time per run (s)",
                                    "relative |L| error at 20 s", 4, 7, names, 1,
                                    "tumble: |L| error vs CPU time"));
  std::ostringstream md;
  md << "### `tumble`: the tennis-racket flip\n\n"
     << "Scene `scenes/tumble.json`: box 1 × 2 × 3 m, 1 kg, ω = (0.01, 2, 0.01) rad/s about "
        "the middle axis, no gravity, 20 s; dt = 1/15 … "
     << dt_label(step_sizes(o.quick).back())
     << " s. Error = geodesic angle ‖log(R_refᵀR)‖ at 20 s against the `tumble_reference` "
        "RKF78 solve at tolerance 1e-13; the reference is known to "
     << recorded_values(o)["wp.tumble_reference_note"]
     << ". Energy error is the largest relative error over the run; |L| error is at 20 s. "
        "CSV: "
     << file_link(o, csv) << ".\n\n"
     << image_link(o, p1, "tumble orientation error vs CPU time") << "\n\n"
     << image_link(o, p2, "tumble energy error vs CPU time") << "\n\n"
     << image_link(o, p3, "tumble |L| error vs CPU time") << "\n\n"
     << "At dt = 1/30 s:\n\n"
     << md_table({"integrator", "angle error (rad)", "energy rel. error", "‖L‖ rel. error",
                  "CPU ms per 20 s run"},
                 rows)
     << "\nWhat it shows: each curve walks from the largest step (left, cheapest) to the "
        "smallest; a steeper descent is a higher order. The orientation error of a body "
        "3.5e-6 from the separatrix is dominated by the flip timing, so schemes that drift "
        "in energy (Euler, midpoint) lose the flip phase, while `splitting` (|L| exact, "
        "energy bounded) and `exact` stay on the right orbit.\n\n";
  return md.str();
}

// ---------------------------------------------------------------- bounce

double lowest_y(const tumble::BodyState& s, const tumble::BodyConstants& c) {
  return s.x.y() - s.R.row(1).cwiseAbs().dot(c.half_extents);
}

const ToiMethod kToiMethods[] = {ToiMethod::bisection, ToiMethod::root};

std::vector<std::string> combo_names() {
  std::vector<std::string> names;
  for (Integrator i : tumble::kIntegrators)
    for (ToiMethod t : kToiMethods)
      names.push_back(std::string(tumble::to_string(i)) + "+" + std::string(tumble::to_string(t)));
  return names;
}

std::string work_precision_bounce(const Options& o, Progress& bar) {
  const tumble::Scene base = bundled("bounce");
  const tumble::World probe(base);
  const tumble::Body& b0 = probe.body(0);
  const double g = -base.world.gravity.y();
  const double e = base.world.floor->restitution;
  const double floor_y = base.world.floor->height;
  const double h0 = lowest_y(b0.s, b0.c) - floor_y;
  // Analytic: impact k at t_k, apex k = e^{2k} h0 at t_k + e^k v1 / g.
  const double v1 = std::sqrt(2.0 * g * h0);
  double t_impact[3], apex[3];
  double t = std::sqrt(2.0 * h0 / g);
  for (int k = 0; k < 3; ++k) {
    t_impact[k] = t;
    apex[k] = std::pow(e, 2.0 * (k + 1)) * h0;
    t += 2.0 * std::pow(e, k + 1) * v1 / g;
  }
  const double t_end = t_impact[2] + std::pow(e, 3) * v1 / g + 0.05;

  const fs::path csv = o.out / "wp_bounce.csv";
  std::vector<std::vector<std::string>> rows;
  double worst_apex1_exact_root = 0.0;
  {
    Csv out(csv, {"method", "dt", "steps", "cpu_s", "apex_err_m", "impact_time_err_s",
                  "apex1_err_m", "apex1_m", "apex2_m", "apex3_m"});
    for (Integrator integ : tumble::kIntegrators) {
      for (ToiMethod toi : kToiMethods) {
        const std::string name =
            std::string(tumble::to_string(integ)) + "+" + std::string(tumble::to_string(toi));
        for (double dt : step_sizes(o.quick)) {
          bar.note("bounce " + name + " " + dt_label(dt));
          const tumble::Scene s = with(base, integ, toi, dt);
          const long steps = std::lround(std::ceil(t_end / dt));
          tumble::World w(s);
          double got_apex[3] = {NAN, NAN, NAN}, got_t[3] = {NAN, NAN, NAN};
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
              prev_vy = vy;
              prev_apex = y + vy * vy / (2.0 * g);
              continue;
            }
            // Apex implied by the last state still rising (exact for a ballistic state).
            if (apexes < impacts && prev_vy > 0.0 && vy <= 0.0) got_apex[apexes++] = prev_apex;
            prev_vy = vy;
            prev_apex = y + vy * vy / (2.0 * g);
          }
          double apex_err = 0.0, t_err = 0.0;
          for (int k = 0; k < 3; ++k) {
            apex_err = std::max(apex_err, std::isnan(got_apex[k]) ? INFINITY
                                                                  : std::fabs(got_apex[k] - apex[k]));
            t_err = std::max(t_err, std::isnan(got_t[k]) ? INFINITY
                                                         : std::fabs(got_t[k] - t_impact[k]));
          }
          const double apex1 = std::isnan(got_apex[0]) ? INFINITY : std::fabs(got_apex[0] - apex[0]);
          if (integ == Integrator::exact && toi == ToiMethod::root)
            worst_apex1_exact_root = std::max(worst_apex1_exact_root, apex1);
          const double cpu = time_run(s, steps, o.quick ? 0.002 : 0.03);
          out.row() << name << dt << steps << cpu << apex_err << t_err << apex1 << got_apex[0]
                    << got_apex[1] << got_apex[2];
          if (std::fabs(dt - 1.0 / 60.0) < 1e-12) {
            rows.push_back({"`" + name + "`", fmt(apex1), fmt(apex_err), fmt(t_err),
                            fmt(cpu * 1e6)});
          }
          bar.tick();
        }
      }
    }
  }
  record_value(o, "wp.bounce_apex1_err.exact.root", fmt(worst_apex1_exact_root, 4));
  const fs::path p1 = plot(o, "wp_bounce_apex",
                           log_plot("wp_bounce.csv", "CPU time per run (s)",
                                    "worst error of the first three apexes (m)", 4, 5,
                                    combo_names(), 1, "bounce: apex error vs CPU time"));
  const fs::path p2 = plot(o, "wp_bounce_time",
                           log_plot("wp_bounce.csv", "CPU time per run (s)",
                                    "worst impact-time error (s)", 4, 6, combo_names(), 1,
                                    "bounce: impact-time error vs CPU time"));
  std::ostringstream md;
  md << "### `bounce`: apexes and impact times\n\n"
     << "Scene `scenes/bounce.json`: flat unit cube, lowest face at " << fmt(h0) << " m, e = "
     << fmt(e) << ", g = " << fmt(g) << " m/s², TOI tolerance "
     << fmt(base.world.toi_tolerance) << " s. Analytic apexes e^{2k}·h = " << fmt(apex[0], 6)
     << ", " << fmt(apex[1], 6) << ", " << fmt(apex[2], 6) << " m; impacts at "
     << fmt(t_impact[0], 8) << ", " << fmt(t_impact[1], 8) << ", " << fmt(t_impact[2], 8)
     << " s. Measured apex = y + v²/2g of the last rising state; measured impact time = "
        "where the first post-impact state's parabola meets the floor (both exact for a "
        "ballistic state, so what is measured is the state's error, not the sampling). "
        "CSV: "
     << file_link(o, csv) << ".\n\n"
     << image_link(o, p1, "bounce apex error vs CPU time") << "\n\n"
     << image_link(o, p2, "bounce impact-time error vs CPU time") << "\n\n"
     << "At dt = 1/60 s:\n\n"
     << md_table({"integrator + TOI", "apex 1 error (m)", "worst apex error (m)",
                  "worst impact-time error (s)", "CPU µs per run"},
                 rows)
     << "\nWhat it shows: flight under gravity alone is a parabola, so every integrator "
        "exact for quadratics (all but explicit Euler and symplectic Euler) is limited only by "
        "the impact search; `root` reaches round-off where `bisection` stops at its "
        "tolerance. First-apex error of `exact`+`root`, worst over every dt: "
     << fmt(worst_apex1_exact_root) << " m.\n\n";
  return md.str();
}

// ---------------------------------------------------------------- seed

/// Event-driven reference for one box on a frictionless floor: exact parabola for the centre,
/// `tumble_reference` (RKF78 at `tol`) for the attitude, impacts located by TOMS 748 on the
/// lowest vertex, answered with the single-vertex impulse j = −(1+e) v_n / (1/m + n·(I⁻¹(r×n))×r).
struct SeedReference {
  Vec3 x, v, L;
  Mat3 R;
  int impacts = 0;
};

SeedReference seed_reference(const tumble::Body& b, const Vec3& gravity, double e, double t_end,
                             double tol) {
  SeedReference s{b.s.x, b.s.P * b.c.inv_mass, b.s.L, b.s.R, 0};
  const Vec3 I = b.c.inertia;
  double t = 0.0;
  constexpr double kScan = 1e-3;  // s between sign checks of the lowest-vertex height
  auto state_at = [&](double tau, Vec3& x, Mat3& R) {
    x = s.x + s.v * tau + 0.5 * gravity * tau * tau;
    R = tau == 0.0 ? s.R
                   : ref::free_rigid_body_attitude(I, s.R, s.L, tau,
                                                   ref::Method::kQuaternionRkf78, tol);
  };
  auto height = [&](double tau) {
    Vec3 x;
    Mat3 R;
    state_at(tau, x, R);
    return x.y() - R.row(1).cwiseAbs().dot(b.c.half_extents);
  };
  while (t < t_end) {
    // Scan this segment for the first crossing (approaching the floor).
    std::vector<double> grid;
    for (double tau = kScan; t + tau < t_end + kScan; tau += kScan) grid.push_back(std::min(tau, t_end - t));
    const auto Rs = ref::free_rigid_body_attitudes(I, s.R, s.L, grid,
                                                   ref::Method::kQuaternionRkf78, tol);
    double lo = 0.0, hi = -1.0;
    for (std::size_t k = 0; k < grid.size(); ++k) {
      const Vec3 x = s.x + s.v * grid[k] + 0.5 * gravity * grid[k] * grid[k];
      if (x.y() - Rs[k].row(1).cwiseAbs().dot(b.c.half_extents) < 0.0) {
        hi = grid[k];
        break;
      }
      lo = grid[k];
    }
    if (hi < 0.0) {  // no impact before t_end
      Vec3 x;
      Mat3 R;
      state_at(t_end - t, x, R);
      s.v += gravity * (t_end - t);
      s.x = x;
      s.R = R;
      return s;
    }
    std::uintmax_t iters = 200;
    const auto root = boost::math::tools::toms748_solve(
        height, lo, hi, boost::math::tools::eps_tolerance<double>(52), iters);
    const double tc = 0.5 * (root.first + root.second);
    Vec3 x;
    Mat3 R;
    state_at(tc, x, R);
    s.x = x;
    s.R = R;
    s.v += gravity * tc;
    t += tc;
    // Lowest vertex and the impulse (frictionless).
    int lowest = 0;
    double ymin = INFINITY;
    for (int i = 0; i < 8; ++i) {
      const Vec3 r = R * tumble::body_vertex(b.c, i);
      if (r.y() < ymin) { ymin = r.y(); lowest = i; }
    }
    const Vec3 r = R * tumble::body_vertex(b.c, lowest);
    const Mat3 inv_I = R * I.cwiseInverse().asDiagonal() * R.transpose();
    const Vec3 n(0.0, 1.0, 0.0);
    const Vec3 omega = inv_I * s.L;
    const double vn = n.dot(s.v + omega.cross(r));
    const double j = -(1.0 + e) * vn / (b.c.inv_mass + n.dot((inv_I * r.cross(n)).cross(r)));
    s.v += j * b.c.inv_mass * n;
    s.L += r.cross(j * n);
    ++s.impacts;
  }
  return s;
}

std::string work_precision_seed(const Options& o, Progress& bar) {
  const tumble::Scene base = bundled("seed");
  const double t_end = 2.5;
  const tumble::World probe(base);
  const tumble::Body& b0 = probe.body(0);
  const double e = base.world.floor->restitution;
  const Vec3 gravity = base.world.gravity;
  const double E0 = tumble::total_energy(b0.s, b0.c, gravity);
  const SeedReference r1 = seed_reference(b0, gravity, e, t_end, 1e-13);
  const SeedReference r2 = seed_reference(b0, gravity, e, t_end, 5e-14);
  const double ref_dx = (r1.x - r2.x).norm();
  const double ref_da = tumble::rotation_angle_between(r1.R, r2.R);

  const fs::path csv = o.out / "wp_seed.csv";
  std::vector<std::vector<std::string>> rows;
  {
    Csv out(csv, {"method", "dt", "steps", "cpu_s", "position_err_m", "angle_err_rad",
                  "energy_rel_drift", "impacts"});
    for (Integrator integ : tumble::kIntegrators) {
      for (ToiMethod toi : kToiMethods) {
        const std::string name =
            std::string(tumble::to_string(integ)) + "+" + std::string(tumble::to_string(toi));
        for (double dt : step_sizes(o.quick)) {
          bar.note("seed " + name + " " + dt_label(dt));
          const tumble::Scene s = with(base, integ, toi, dt);
          const long steps = std::lround(t_end / dt);
          tumble::World w(s);
          for (long i = 0; i < steps; ++i) w.step();
          const tumble::Body& b = w.body(0);
          const double dx = (b.s.x - r1.x).norm();
          const double da = tumble::rotation_angle_between(r1.R, b.s.R);
          const double de = std::fabs(tumble::total_energy(b.s, b.c, gravity) - E0) / std::fabs(E0);
          const double cpu = time_run(s, steps, o.quick ? 0.002 : 0.03);
          out.row() << name << dt << steps << cpu << dx << da << de
                    << static_cast<long long>(w.total_impacts());
          if (std::fabs(dt - 1.0 / 30.0) < 1e-12) {
            rows.push_back({"`" + name + "`", fmt(dx), fmt(da), fmt(de),
                            std::to_string(w.total_impacts()), fmt(cpu * 1e6)});
          }
          bar.tick();
        }
      }
    }
  }
  const fs::path p1 = plot(o, "wp_seed_position",
                           log_plot("wp_seed.csv", "CPU time per run (s)",
                                    "final position error (m)", 4, 5, combo_names(), 1,
                                    "seed (e = 1): final position error vs CPU time"));
  const fs::path p2 = plot(o, "wp_seed_energy",
                           log_plot("wp_seed.csv", "CPU time per run (s)",
                                    "relative energy drift at the end", 4, 7, combo_names(), 1,
                                    "seed (e = 1): energy drift vs CPU time"));
  std::ostringstream md;
  md << "### `seed`: the tumbling box on an elastic floor\n\n"
     << "Scene `scenes/seed.json` (unit box from 3 m, ω = (1.2, 0.4, −0.8) rad/s, e = " << fmt(e)
     << ", frictionless), " << t_end << " s, " << r1.impacts
     << " impacts in the reference. Reference: computed by the bench — exact parabola for the "
        "centre, `tumble_reference` RKF78 at tolerance 1e-13 for the attitude, impacts "
        "located by TOMS 748 on the lowest vertex and answered with the single-vertex "
        "frictionless impulse. Halving the tolerance moves its final position by "
     << fmt(ref_dx) << " m and its attitude by " << fmt(ref_da) << " rad. CSV: "
     << file_link(o, csv) << ".\n\n"
     << image_link(o, p1, "seed final position error vs CPU time") << "\n\n"
     << image_link(o, p2, "seed energy drift vs CPU time") << "\n\n"
     << "At dt = 1/30 s (the seed's own step):\n\n"
     << md_table({"integrator + TOI", "position error (m)", "angle error (rad)",
                  "energy drift (rel.)", "impacts", "CPU µs per run"},
                 rows)
     << "\nWhat it shows: with impacts in the run, the error of every scheme is set by how "
        "well the impact instant and the pre-impact attitude are known; bisection stops at "
        "its tolerance, root-finding on the trajectory goes to round-off when the flight "
        "itself is exact.\n\n";
  return md.str();
}

}  // namespace

void run_work_precision(const Options& o) {
  const std::size_t n = step_sizes(o.quick).size();
  Progress bar("work-precision", n * 6 + n * 12 + n * 12);
  std::string md =
      "## Work–precision\n\n"
      "The CPU axis of every plot in this section (and the CPU column of every table) is "
      "**per run**: the CPU time of the benchmark thread to simulate the whole interval of the "
      "scene at that dt (20 s of `tumble`, the three bounces of `bounce`, 2.5 s of `seed`), "
      "not per step. Each point is the mean over back-to-back repeats of the run (as many as "
      "fit in 50 ms for `tumble` and 30 ms for the others, at most 50), so a smaller dt costs "
      "proportionally more steps. Errors are those of the run's final (or listed) state.\n\n";
  md += work_precision_tumble(o, bar);
  md += work_precision_bounce(o, bar);
  md += work_precision_seed(o, bar);
  write_section(o, "work_precision", md);
}

}  // namespace tumble_bench
