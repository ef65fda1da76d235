/// peers: medians of the landing runs, shared by the CSV and the Markdown.
#include <cmath>

#include "peers/peers.hpp"

namespace tumble_bench::peers {
namespace {

LandingRow landing_row(const Contender& c, std::size_t n, const std::vector<landing::Run>& runs) {
  LandingRow row;
  row.engine = c.name;
  row.n = n;
  row.sleeps = c.sleeps;
  std::vector<double> all, head;
  for (const landing::Run& r : runs) {
    if (row.trouble.empty()) row.trouble = r.trouble;
    if (!std::isfinite(r.ns_per_body_step)) continue;
    all.push_back(r.ns_per_body_step);
    head.push_back(r.ns_per_body_step_head);
  }
  row.ns = median(all);
  row.ns_head = median(head);
  if (runs.empty()) return row;
  // Deterministic behaviour: the first run (which looked past the timed run) speaks for all.
  const landing::Run& first = runs.front();
  row.impacts_per_box = first.impacts_per_box;
  row.asleep_fraction = first.asleep_fraction;
  row.all_asleep_at = first.all_asleep_at;
  row.watched_until = first.watched_until;
  return row;
}

}  // namespace

std::vector<LandingRow> landing_rows(const Measurement& m) {
  std::vector<LandingRow> rows;
  for (std::size_t n : m.landing_sizes) {
    const std::size_t first = rows.size();
    for (const Contender& c : m.fast) {
      const auto e = m.landing.find(c.name);
      const bool ran = e != m.landing.end() && e->second.count(n);
      rows.push_back(landing_row(c, n, ran ? e->second.at(n) : std::vector<landing::Run>{}));
    }
    const LandingRow& t = rows[first];  // Tumble
    for (std::size_t i = first; i < rows.size(); ++i) {
      rows[i].ratio = rows[i].ns / t.ns;
      rows[i].ratio_head = rows[i].ns_head / t.ns_head;
    }
  }
  return rows;
}

}  // namespace tumble_bench::peers
