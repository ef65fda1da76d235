/// peers: measure, record, report (see peers/peers.hpp).
#include "benchmarks.hpp"
#include "peers/peers.hpp"

namespace tumble_bench {

void run_peers(const Options& o) {
  const peers::Measurement m = peers::measure(o);
  const peers::Files files = peers::record(o, m);
  peers::report(o, m, files);
}

}  // namespace tumble_bench
