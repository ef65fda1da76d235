/// skip: 10,000 resting boxes + 10 falling against the 10 alone, ms per step; the cost must
/// follow the awake bodies from the first step.
#include <cmath>
#include <sstream>

#include "benchmarks.hpp"
#include "report.hpp"
#include "scenes.hpp"
#include "tumble/world.hpp"

namespace tumble_bench {

void run_skip(const Options& o) {
  const std::size_t resting = o.quick ? 1000 : 10000;
  constexpr std::size_t kFalling = 10;
  const long steps = o.quick ? 30 : 120;  // dt = 1/60 s
  const tumble::Scene full = resting_and_falling(resting, kFalling);
  const tumble::Scene alone = resting_and_falling(0, kFalling);
  const int reps = std::max(3, o.repeats);
  Progress bar("skip", static_cast<std::size_t>(reps) * 2);
  std::vector<std::vector<double>> ms_full(steps), ms_alone(steps);
  std::vector<double> awake(steps);
  for (int r = 0; r < reps; ++r) {  // interleaved: full, alone, full, alone …
    for (int which = 0; which < 2; ++which) {
      tumble::World w(which == 0 ? full : alone);
      for (long i = 0; i < steps; ++i) {
        const double t0 = thread_cpu_seconds();
        w.step();
        const double ms = (thread_cpu_seconds() - t0) * 1e3;
        (which == 0 ? ms_full : ms_alone)[i].push_back(ms);
        if (which == 0) awake[i] = w.last_step().awake;
      }
      bar.tick();
    }
  }
  const fs::path csv = o.out / "skip.csv";
  double sum_full = 0.0, sum_alone = 0.0;
  {
    Csv out(csv, {"step", "ms_full", "ms_alone", "awake_full"});
    for (long i = 0; i < steps; ++i) {
      const double f = median(ms_full[i]), a = median(ms_alone[i]);
      sum_full += f;
      sum_alone += a;
      out.row() << i + 1 << f << a << awake[i];
    }
  }
  const double mean_full = sum_full / steps, mean_alone = sum_alone / steps;
  const double first = median(ms_full[0]);
  record_value(o, "skip.ms_per_step", fmt(mean_full, 4));
  record_value(o, "skip.ms_per_step_alone", fmt(mean_alone, 4));
  record_value(o, "skip.first_step_ms", fmt(first, 4));
  record_value(o, "skip.first_step_ms_alone", fmt(median(ms_alone[0]), 4));
  record_value(o, "skip.awake_after_step1", fmt(awake[0], 6));
  record_value(o, "skip.resting", std::to_string(resting));
  std::ostringstream g;
  g << "set logscale y\nset title 'skip: " << resting << " resting + 10 falling vs 10 alone'\n"
    << "set xlabel 'step (dt = 1/60 s)'\nset ylabel 'CPU ms per step'\n"
    << "set y2label 'awake bodies'\nset y2tics\nset logscale y2\nset ytics nomirror\n"
    << "plot 'skip.csv' skip 1 using 1:2 with lines lw 2 title '" << resting
    << " resting + 10 falling', \\\n"
    << "     'skip.csv' skip 1 using 1:3 with lines lw 2 title '10 falling alone', \\\n"
    << "     'skip.csv' skip 1 using 1:4 axes x1y2 with lines dt 2 title 'awake (full scene)', \\\n"
    << "     0.2 with lines lc rgb 'gray' dt 3 title 'goal 0.2 ms'\n";
  const fs::path p = plot(o, "skip", g.str());
  std::ostringstream md;
  md << "## Skip what the scene doesn't need\n\n"
     << resting << " unit cubes placed at rest on a frictionless floor (e = 0.5) plus 10 "
        "dropped from 2 m with spin, against the 10 alone; dt = 1/60 s, "
     << steps << " steps, median of " << reps
     << " interleaved runs per step (CPU time of the stepping thread, world built untimed). "
     << (awake[0] <= static_cast<double>(kFalling)
             ? "The engine puts a body placed still on a face on the floor to sleep when the "
               "world is built, so the resting boxes are asleep from the start: after step 1 "
               "only " + fmt(awake[0]) + " bodies are awake. "
             : "The resting boxes start awake (" + fmt(awake[0]) +
                   " bodies awake after step 1), so what is measured is how fast the engine "
                   "stops paying for them. ")
     << "CSV: "
     << file_link(o, csv) << ".\n\n"
     << image_link(o, p, "skip: ms per step") << "\n\n"
     << md_table({"scene", "mean ms per step", "first step ms", "awake after step 1"},
                 {{std::to_string(resting) + " resting + 10 falling", fmt(mean_full), fmt(first),
                   fmt(awake[0])},
                  {"10 falling alone", fmt(mean_alone), fmt(median(ms_alone[0])), "10"}})
     << "\nWhat it shows: the ratio of the two curves is the price of the sleeping bodies. "
        "Goal: ≤ 0.2 ms per step with the cost following the awake bodies from the first "
        "step; if the first steps cost more, resting bodies are being integrated until the "
        "sleep timer (0.5 s) catches them.\n\n";
  write_section(o, "skip", md.str());
}

}  // namespace tumble_bench
