/// skip: 10,000 resting boxes + 10 falling against the 10 alone, ms per step; the cost must
/// follow the awake bodies from the first step. Measure (per-step medians), record (skip.csv,
/// headline values, plot), report (bench/text/skip.md).
#include <cmath>
#include <sstream>

#include "benchmarks.hpp"
#include "report.hpp"
#include "scenes.hpp"
#include "text.hpp"
#include "tumble/world.hpp"

namespace tumble_bench {
namespace {

constexpr std::size_t kFalling = 10;

/// Per-step medians of both scenes.
struct SkipMeasurement {
  std::size_t resting = 0;
  long steps = 0;
  int reps = 0;
  std::vector<double> ms_full, ms_alone;  // median CPU ms of step i
  std::vector<double> awake;              // bodies awake after step i (full scene)
  double mean_full = 0.0, mean_alone = 0.0;
};

SkipMeasurement measure_skip(const Options& o) {
  SkipMeasurement m;
  m.resting = o.quick ? 1000 : 10000;
  m.steps = o.quick ? 30 : 120;  // dt = 1/60 s
  m.reps = std::max(3, o.repeats);
  const tumble::Scene scenes[2] = {resting_and_falling(m.resting, kFalling),
                                   resting_and_falling(0, kFalling)};
  Progress bar("skip", static_cast<std::size_t>(m.reps) * 2);
  std::vector<std::vector<double>> ms[2] = {std::vector<std::vector<double>>(m.steps),
                                            std::vector<std::vector<double>>(m.steps)};
  m.awake.resize(m.steps);
  for (int r = 0; r < m.reps; ++r) {  // interleaved: full, alone, full, alone …
    for (int which = 0; which < 2; ++which) {
      tumble::World w(scenes[which]);
      for (long i = 0; i < m.steps; ++i) {
        const double t0 = thread_cpu_seconds();
        w.step();
        ms[which][i].push_back((thread_cpu_seconds() - t0) * 1e3);
        if (which == 0) m.awake[i] = w.last_step().awake;
      }
      bar.tick();
    }
  }
  for (long i = 0; i < m.steps; ++i) {
    m.ms_full.push_back(median(ms[0][i]));
    m.ms_alone.push_back(median(ms[1][i]));
    m.mean_full += m.ms_full.back() / static_cast<double>(m.steps);
    m.mean_alone += m.ms_alone.back() / static_cast<double>(m.steps);
  }
  return m;
}

std::string skip_plot(const SkipMeasurement& m) {
  std::ostringstream g;
  g << "set logscale y\nset title 'skip: " << m.resting << " resting + 10 falling vs 10 alone'\n"
    << "set xlabel 'step (dt = 1/60 s)'\nset ylabel 'CPU ms per step'\n"
    << "set y2label 'awake bodies'\nset y2tics\nset logscale y2\nset ytics nomirror\n"
    << "plot 'skip.csv' skip 1 using 1:2 with lines lw 2 title '" << m.resting
    << " resting + 10 falling', \\\n"
    << "     'skip.csv' skip 1 using 1:3 with lines lw 2 title '10 falling alone', \\\n"
    << "     'skip.csv' skip 1 using 1:4 axes x1y2 with lines dt 2 title 'awake (full scene)', \\\n"
    << "     0.2 with lines lc rgb 'gray' dt 3 title 'goal 0.2 ms'\n";
  return g.str();
}

/// skip.csv, the headline values and the plot; returns the SVG path.
fs::path record_skip(const Options& o, const SkipMeasurement& m) {
  {
    Csv out(o.out / "skip.csv", {"step", "ms_full", "ms_alone", "awake_full"});
    for (long i = 0; i < m.steps; ++i)
      out.row() << i + 1 << m.ms_full[i] << m.ms_alone[i] << m.awake[i];
  }
  record_value(o, "skip.ms_per_step", fmt(m.mean_full, 4));
  record_value(o, "skip.ms_per_step_alone", fmt(m.mean_alone, 4));
  record_value(o, "skip.first_step_ms", fmt(m.ms_full[0], 4));
  record_value(o, "skip.first_step_ms_alone", fmt(m.ms_alone[0], 4));
  record_value(o, "skip.awake_after_step1", fmt(m.awake[0], 6));
  record_value(o, "skip.resting", std::to_string(m.resting));
  return plot(o, "skip", skip_plot(m));
}

void report_skip(const Options& o, const SkipMeasurement& m, const fs::path& svg) {
  const std::string start_state =
      m.awake[0] <= static_cast<double>(kFalling)
          ? "The engine puts a body placed still on a face on the floor to sleep when the world "
            "is built, so the resting boxes are asleep from the start: after step 1 only " +
                fmt(m.awake[0]) + " bodies are awake."
          : "The resting boxes start awake (" + fmt(m.awake[0]) +
                " bodies awake after step 1), so what is measured is how fast the engine stops "
                "paying for them.";
  const Fields f{
      {"resting", std::to_string(m.resting)},
      {"steps", std::to_string(m.steps)},
      {"reps", std::to_string(m.reps)},
      {"start_state", start_state},
      {"csv", file_link(o, o.out / "skip.csv")},
      {"plot", image_link(o, svg, "skip: ms per step")},
      {"table", md_table({"scene", "mean ms per step", "first step ms", "awake after step 1"},
                         {{std::to_string(m.resting) + " resting + 10 falling",
                           fmt(m.mean_full), fmt(m.ms_full[0]), fmt(m.awake[0])},
                          {"10 falling alone", fmt(m.mean_alone), fmt(m.ms_alone[0]), "10"}})},
  };
  write_section(o, "skip", fill_template("skip", f));
}

}  // namespace

void run_skip(const Options& o) {
  const SkipMeasurement m = measure_skip(o);
  report_skip(o, m, record_skip(o, m));
}

}  // namespace tumble_bench
