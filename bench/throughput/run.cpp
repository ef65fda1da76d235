/// throughput: measure, record, report (see throughput/throughput.hpp).
#include "benchmarks.hpp"
#include "throughput/throughput.hpp"

namespace tumble_bench {

void run_throughput(const Options& o) {
  const throughput::Measurement m = throughput::measure(o);
  const throughput::Files files = throughput::record(o, m);
  throughput::report(o, m, files);
}

}  // namespace tumble_bench
