/// throughput: medians of the measurement, shared by the CSV and the Markdown.
#include <algorithm>

#include "throughput/throughput.hpp"

namespace tumble_bench::throughput {

std::vector<ScalingRow> scaling_rows(const Measurement& m) {
  std::vector<ScalingRow> rows;
  for (std::size_t n : m.cfg.sizes) {
    for (BoxShape shape : kShapes) {
      const std::vector<Run>& rs = m.scaling.at({shape, n});
      std::vector<double> all, head, awake;
      for (const Run& r : rs) {
        all.push_back(r.ns_per_body_step);
        head.push_back(r.ns_per_body_step_head);
        awake.push_back(r.ns_per_body_step / std::max(r.awake_fraction, 1e-12));
      }
      ScalingRow row{.shape = shape, .n = n};
      row.full = n < m.cfg.n_big;
      row.steps = row.full ? m.cfg.steps : m.cfg.head_steps;
      row.runs = rs.size();
      row.ns = row.full ? median(all) : NAN;
      row.ns_head = median(head);
      row.ns_awake = row.full ? median(awake) : NAN;
      row.last = rs.back();
      rows.push_back(row);
    }
  }
  return rows;
}

std::vector<LandingRow> landing_rows(const Measurement& m) {
  std::vector<LandingRow> rows;
  for (const auto& [n, runs] : m.landing) {
    LandingRow row;
    row.n = n;
    row.runs = runs.size();
    std::vector<double> all, head;
    for (const landing::Run& r : runs) {
      all.push_back(r.ns_per_body_step);
      head.push_back(r.ns_per_body_step_head);
      if (row.trouble.empty()) row.trouble = r.trouble;
    }
    row.ns = median(all);
    row.ns_head = median(head);
    // The behaviour is deterministic: the first run (the one that looked past the timed run
    // for the moment every box sleeps) speaks for all.
    const landing::Run& first = runs.front();
    row.impacts_per_box = first.impacts_per_box;
    row.asleep_fraction = first.asleep_fraction;
    row.all_asleep_at = first.all_asleep_at;
    row.watched_until = first.watched_until;
    rows.push_back(row);
  }
  return rows;
}

}  // namespace tumble_bench::throughput
