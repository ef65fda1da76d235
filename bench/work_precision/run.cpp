/// work-precision: each scene measured, recorded and reported in turn (see work_precision.hpp).
#include "benchmarks.hpp"
#include "report.hpp"
#include "text.hpp"
#include "work_precision/work_precision.hpp"

namespace tumble_bench {

void run_work_precision(const Options& o) {
  const std::size_t n = wp::step_sizes(o.quick).size();
  Progress bar("work-precision", n * 6 + n * 12 + n * 12);
  const wp::TumbleMeasurement tumble = wp::measure_tumble(o, bar);
  const std::string tumble_md = wp::report_tumble(o, tumble, wp::record_tumble(o, tumble));
  const wp::BounceMeasurement bounce = wp::measure_bounce(o, bar);
  const std::string bounce_md = wp::report_bounce(o, bounce, wp::record_bounce(o, bounce));
  const wp::SeedMeasurement seed = wp::measure_seed(o, bar);
  const std::string seed_md = wp::report_seed(o, seed, wp::record_seed(o, seed));
  write_section(o, "work_precision",
                fill_template("work_precision",
                              {{"tumble", tumble_md}, {"bounce", bounce_md}, {"seed", seed_md}}));
}

}  // namespace tumble_bench
