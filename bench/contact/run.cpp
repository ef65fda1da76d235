/// contact: measure, record, report (see contact/contact.hpp).
#include "benchmarks.hpp"
#include "contact/contact.hpp"

namespace tumble_bench {

void run_contact(const Options& o) {
  const contact::Measurement m = contact::measure(o);
  const fs::path svg = contact::record(o, m);
  contact::report(o, m, svg);
}

}  // namespace tumble_bench
