/// pile-precision: measure, record, report (see pile_precision/pile_precision.hpp).
#include "benchmarks.hpp"
#include "pile_precision/pile_precision.hpp"

namespace tumble_bench {

void run_pile_precision(const Options& o) {
  const pile_precision::Measurement m = pile_precision::measure(o);
  const fs::path svg = pile_precision::record(o, m);
  pile_precision::report(o, m, svg);
}

}  // namespace tumble_bench
