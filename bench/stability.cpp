/// stability: stress tests, each with its pass criterion and the measured figure. Measure
/// (one Row per test), record (CSV, the table for the closing note), report
/// (bench/text/stability.md).
#include <algorithm>
#include <cmath>
#include <sstream>

#include "benchmarks.hpp"
#include "report.hpp"
#include "scenes.hpp"
#include "text.hpp"
#include "tumble/world.hpp"

namespace tumble_bench {
namespace {

using tumble::Integrator;
using tumble::Vec3;

struct Row {
  std::string test, integrator, criterion, measured;
  bool pass;
};

std::string name(Integrator i) { return std::string(tumble::to_string(i)); }

double lowest_y(const tumble::Body& b) {
  return b.s.x.y() - b.s.R.row(1).cwiseAbs().dot(b.c.half_extents);
}

/// Long free spin: energy and |L| drift and ‖RᵀR − I‖ after `steps` steps.
Row long_run(Integrator integ, long steps) {
  tumble::Scene s = bundled("tumble");
  s.world.integrator = integ;
  s.world.dt = 1.0 / 60.0;
  tumble::World w(s);
  const tumble::Body& b = w.body(0);
  const double E0 = tumble::kinetic_energy(b.s, b.c), L0 = b.s.L.norm();
  for (long i = 0; i < steps; ++i) w.step();
  const double dE = std::fabs(tumble::kinetic_energy(b.s, b.c) - E0) / E0;
  const double dL = std::fabs(b.s.L.norm() - L0) / L0;
  const double orth = tumble::orthonormality_error(b.s.R);
  const bool finite = w.frozen_count() == 0;
  return {std::to_string(steps) + " steps, tumble, dt = 1/60", name(integ),
          "finite; ΔE/E ≤ 1e-3; Δ‖L‖/‖L‖ ≤ 1e-9; ‖RᵀR−I‖ ≤ 1e-12",
          "ΔE/E " + fmt(dE) + ", Δ‖L‖ " + fmt(dL) + ", ‖RᵀR−I‖ " + fmt(orth),
          finite && dE <= 1e-3 && dL <= 1e-9 && orth <= 1e-12};
}

/// ω = 1000 rad/s on the 1×2×3 box at dt = 1/30 for 10 s.
Row fast_spin(Integrator integ) {
  tumble::Scene s = free_spin({1, 2, 3}, 1.0, Vec3(1, 1, 1).normalized() * 1000.0, 1.0 / 30.0);
  s.world.integrator = integ;
  tumble::World w(s);
  const tumble::Body& b = w.body(0);
  const double E0 = tumble::kinetic_energy(b.s, b.c), L0 = b.s.L.norm();
  for (int i = 0; i < 300; ++i) w.step();
  const double dE = std::fabs(tumble::kinetic_energy(b.s, b.c) - E0) / E0;
  const double dL = std::fabs(b.s.L.norm() - L0) / L0;
  const bool finite = w.frozen_count() == 0;
  return {"ω = 1000 rad/s, dt = 1/30, 10 s", name(integ), "finite; ΔE/E ≤ 1e-2; Δ‖L‖/‖L‖ ≤ 1e-6",
          finite ? "ΔE/E " + fmt(dE) + ", Δ‖L‖ " + fmt(dL) : "frozen (non-finite)",
          finite && dE <= 1e-2 && dL <= 1e-6};
}

/// Thin plate at 100 rad/s near its middle axis: largest dt (1/1000 … 1/15) that stays stable.
Row thin_plate(Integrator integ, bool quick) {
  const double dts[] = {1.0 / 1000, 1.0 / 500, 1.0 / 240, 1.0 / 120, 1.0 / 60, 1.0 / 30, 1.0 / 15};
  double largest = 0.0;
  for (double dt : dts) {
    tumble::Scene s = free_spin({1, 0.1, 0.01}, 1.0, Vec3(0.1, 100.0, 0.1), dt);
    s.world.integrator = integ;
    tumble::World w(s);
    const tumble::Body& b = w.body(0);
    const double E0 = tumble::kinetic_energy(b.s, b.c), L0 = b.s.L.norm();
    const long steps = std::lround((quick ? 1.0 : 10.0) / dt);
    bool ok = true;
    for (long i = 0; i < steps && ok; ++i) {
      w.step();
      ok = w.frozen_count() == 0 &&
           tumble::kinetic_energy(b.s, b.c) <= E0 * 1.01 &&
           std::fabs(b.s.L.norm() - L0) <= 1e-6 * L0;
    }
    if (ok) largest = dt;
  }
  return {std::string("thin plate 1×0.1×0.01, ω = 100 rad/s, ") + (quick ? "1 s" : "10 s"),
          name(integ), "stable (energy ≤ +1 %, ‖L‖ to 1e-6) at dt = 1/60",
          largest > 0 ? "largest stable dt " + dt_label(largest) : "unstable at 1/1000",
          largest >= 1.0 / 60.0 - 1e-12};
}

/// A unit cube resting on the floor for `seconds` of simulated time.
Row resting(Integrator integ, double seconds) {
  tumble::Scene s = bundled("resting");
  s.bodies.resize(1);
  s.world.integrator = integ;
  tumble::World w(s);
  const tumble::Body& b = w.body(0);
  const Vec3 x0 = b.s.x;
  const double E0 = tumble::total_energy(b.s, b.c, s.world.gravity);
  const long steps = std::lround(seconds / s.world.dt);
  double sink = 0.0;
  for (long i = 0; i < steps; ++i) {
    w.step();
    sink = std::max(sink, -lowest_y(b));
  }
  const double drift = Vec3(b.s.x.x() - x0.x(), 0.0, b.s.x.z() - x0.z()).norm();
  const double dE = std::fabs(tumble::total_energy(b.s, b.c, s.world.gravity) - E0);
  return {"cube resting " + fmt(seconds / 3600.0) + " h, dt = 1/60", name(integ),
          "sink ≤ 1e-6 m; drift ≤ 1e-9 m; ΔE ≤ 1e-9 J (absolute)",
          "sink " + fmt(sink) + " m, drift " + fmt(drift) + " m, ΔE " + fmt(dE) + " J",
          sink <= 1e-6 && drift <= 1e-9 && dE <= 1e-9};
}

/// Zeno: the flat cube from 1 m with restitution e; time to rest against h-series sum.
Row zeno(double e) {
  tumble::Scene s = bundled("bounce");
  s.world.floor->restitution = e;
  s.world.dt = 1.0 / 60.0;
  tumble::World w(s);
  const double g = -s.world.gravity.y();
  const double t1 = std::sqrt(2.0 * 1.0 / g);
  const double t_rest = t1 * (1.0 + e) / (1.0 - e);  // Σ of the geometric series of flights
  double t_still = NAN;
  for (int i = 0; i < 60 * 30 && std::isnan(t_still); ++i) {
    w.step();
    if (w.body(0).activity == tumble::Activity::asleep ||
        (w.body(0).s.P.norm() < 1e-6 && lowest_y(w.body(0)) < 1e-6))
      t_still = w.time();
  }
  const long long impacts = static_cast<long long>(w.total_impacts());
  const bool ok = !std::isnan(t_still) && t_still <= t_rest + 1.0 && impacts <= 200;
  return {"Zeno, e = " + fmt(e) + ", from 1 m", "exact",
          "at rest within 1 s (+0.5 s sleep timer) of the analytic " + fmt(t_rest, 4) +
              " s; ≤ 200 impacts",
          std::to_string(impacts) + " impacts, still at " + fmt(t_still, 4) + " s", ok};
}

/// Masses 1e-6 … 1e6 kg: first apex of `bounce` must not depend on mass.
Row masses(bool quick) {
  double worst = 0.0;
  for (double m = 1e-6; m <= 1e6 * 1.0001; m *= quick ? 1e6 : 1e3) {
    tumble::Scene s = bundled("bounce");
    s.bodies[0].mass = m;
    s.world.dt = 1.0 / 60.0;
    tumble::World w(s);
    const double g = -s.world.gravity.y();
    double prev = 0.0, apex = NAN;
    bool rising = false;
    for (int i = 0; i < 120 && std::isnan(apex); ++i) {
      w.step();
      const double vy = w.body(0).s.P.y() / m;
      const double y = lowest_y(w.body(0));
      if (vy > 0) {
        rising = true;
        prev = y + vy * vy / (2 * g);
      } else if (rising) {
        apex = prev;
      }
    }
    worst = std::max(worst, std::isnan(apex) ? INFINITY : std::fabs(apex - 0.25));
  }
  return {"masses 1e-6 … 1e6 kg, bounce", "exact", "first apex within 1e-9 m for every mass",
          "worst apex error " + fmt(worst) + " m", worst <= 1e-9};
}

/// One step of 0.5 s from 1 m at 0 and at −100 m/s: no tunnelling.
Row long_step(double v) {
  tumble::Scene s = bundled("bounce");
  s.bodies[0].velocity = {0.0, v, 0.0};
  tumble::World w(s);
  w.step(0.5);
  const double y = lowest_y(w.body(0));
  return {"one step of 0.5 s, v0 = " + fmt(v) + " m/s", "exact", "lowest vertex ≥ −1e-9 m",
          "lowest vertex " + fmt(y) + " m, " + std::to_string(w.total_impacts()) + " impacts",
          y >= -1e-9};
}

/// Every test on every integrator where it applies, in table order.
struct Measurement {
  long long_steps = 0;        // steps of the long runs
  double rest_seconds = 0.0;  // simulated time of the resting runs, s
  std::vector<Row> rows;
};

Measurement measure(const Options& o) {
  Measurement m;
  m.long_steps = o.quick ? 10000 : 1000000;
  m.rest_seconds = o.quick ? 60.0 : 3600.0;
  const std::size_t total = std::size(tumble::kIntegrators) * 4 + 3 + 1 + 2;
  Progress bar("stability", total);
  auto add = [&](Row r) {
    m.rows.push_back(std::move(r));
    bar.tick();
  };
  for (Integrator i : tumble::kIntegrators) {
    bar.note("long run " + name(i));
    add(long_run(i, m.long_steps));
  }
  for (Integrator i : tumble::kIntegrators) add(fast_spin(i));
  for (Integrator i : tumble::kIntegrators) {
    bar.note("thin plate " + name(i));
    add(thin_plate(i, o.quick));
  }
  for (Integrator i : tumble::kIntegrators) {
    bar.note("resting " + name(i));
    add(resting(i, m.rest_seconds));
  }
  for (double e : {0.0, 0.5, 0.9}) add(zeno(e));
  add(masses(o.quick));
  add(long_step(0.0));
  add(long_step(-100.0));
  return m;
}

int passed(const Measurement& m) {
  return static_cast<int>(std::count_if(m.rows.begin(), m.rows.end(),
                                        [](const Row& r) { return r.pass; }));
}

/// stability.csv, stability_table.md (the closing note quotes it) and the headline value;
/// returns the Markdown table.
std::string record(const Options& o, const Measurement& m) {
  std::vector<std::vector<std::string>> table;
  {
    Csv out(o.out / "stability.csv", {"test", "integrator", "criterion", "measured", "pass"});
    for (const Row& r : m.rows) {
      out.row() << r.test << r.integrator << r.criterion << r.measured << (r.pass ? "yes" : "no");
      table.push_back({r.test, "`" + r.integrator + "`", r.criterion, r.measured,
                       r.pass ? "pass" : "**FAIL**"});
    }
  }
  const std::string t = md_table({"test", "integrator", "criterion", "measured", "result"}, table);
  std::ofstream(o.out / "stability_table.md") << t;
  record_value(o, "stability.passed",
               std::to_string(passed(m)) + "/" + std::to_string(m.rows.size()));
  return t;
}

void report(const Options& o, const Measurement& m, const std::string& table) {
  const Fields f{
      {"passed", std::to_string(passed(m))},
      {"tests", std::to_string(m.rows.size())},
      {"long_steps", std::to_string(m.long_steps)},
      {"rest_hours", fmt(m.rest_seconds / 3600.0)},
      {"csv", file_link(o, o.out / "stability.csv")},
      {"table", table},
  };
  write_section(o, "stability", fill_template("stability", f));
}

}  // namespace

void run_stability(const Options& o) {
  const Measurement m = measure(o);
  report(o, m, record(o, m));
}

}  // namespace tumble_bench
