/// stages: measure, record, report (see stages/stages.hpp).
#include "benchmarks.hpp"
#include "stages/stages.hpp"

namespace tumble_bench {

void run_stages(const Options& o) {
  const stages::Measurement m = stages::measure(o);
  stages::report(o, m, stages::record(o, m));
}

}  // namespace tumble_bench
