/// contact, record: contact.csv, the headline values in summary.csv and the gnuplot bar chart.
#include <cmath>
#include <iostream>
#include <sstream>

#include "contact/contact.hpp"
#include "report.hpp"

namespace tumble_bench::contact {
namespace {

void print(const Row& row) {
  std::cerr << "  " << row.scene << " " << row.engine << ": " << fmt(row.ms) << " ms/step"
            << (row.engine == "tumble" ? "" : ", peer/Tumble " + fmt(row.ratio))
            << ", penetration " << fmt(row.penetration) << " m, asleep " << row.asleep
            << (row.scene == "tower" ? ", drift " + fmt(row.tower_drift) + " m" : "")
            << (row.stands != "–" ? ", top box moved " + fmt(row.top_moved) + " m" : "")
            << (row.note.empty() ? "" : " [" + row.note.substr(0, 100) + "]") << '\n';
}

/// Headline values of one scene (keys contact.<scene>.*).
void record_scene(const Options& o, const SceneResult& r, const std::vector<Row>& rs) {
  const Row& t = rs.front();  // Tumble
  double fastest = NAN;
  std::string fastest_name = "none";
  for (const Row& row : rs)  // a peer: not Tumble on one thread, nor on several (tumble-2t)
    if (row.engine.rfind("tumble", 0) != 0 && row.valid && !(row.ms >= fastest)) {
      fastest = row.ms;
      fastest_name = row.engine;
    }
  const std::string k = "contact." + r.spec.name + ".";
  const EngineResult& e = r.engine.at("tumble");
  record_value(o, k + "tumble_ms", fmt(t.ms, 4));
  record_value(o, k + "fastest_peer", fastest_name);
  record_value(o, k + "ratio_to_fastest", fmt(fastest / t.ms, 4));
  record_value(o, k + "tumble_penetration_m", fmt(e.sleeping.penetration, 4));
  record_value(o, k + "tumble_asleep_s", fmt(e.sleeping.asleep_at, 4));
  if (r.spec.name == "tower")
    record_value(o, k + "tumble_drift_60s_m", fmt(e.tower_awake.drift, 4));
  if (r.spec.stack) {
    record_value(o, k + "tumble_top_moved_m", fmt(t.top_moved, 4));
    record_value(o, k + "tumble_stands", t.stands);
  }
}

std::string plot_script(const Measurement& m) {
  std::ostringstream g;
  g << "set logscale y\nset title 'box–box contact: CPU ms per step while every body is awake'\n"
    << "set ylabel 'CPU ms per step'\nset xrange [-0.6:" << m.scenes.size() - 0.4 << "]\n"
    << "set xtics (";
  for (std::size_t i = 0; i < m.scenes.size(); ++i)
    g << (i ? ", " : "") << "'" << m.scenes[i].spec.name << " (" << m.scenes[i].bodies << ")' "
      << i;
  const double n = static_cast<double>(m.engines.size());
  g << ")\nset key top left\nset boxwidth " << 0.8 / n
    << "\nset style fill solid 0.8\nset datafile separator ','\nplot ";
  for (std::size_t ei = 0; ei < m.engines.size(); ++ei) {
    const double off = (static_cast<double>(ei) - (n - 1.0) / 2.0) * 0.8 / n;
    g << (ei ? ", \\\n     " : "") << "'contact.csv' skip 1 using (strcol(3) eq '"
      << m.engines[ei].name << "' ? $2 + (" << off << ") : 1/0):7 with boxes title '"
      << m.engines[ei].name << "'";
  }
  return g.str();
}

}  // namespace

fs::path record(const Options& o, const Measurement& m) {
  {
    Csv out(o.out / "contact.csv",
            {"scene", "scene_index", "engine", "engine_index", "bodies", "timed_steps",
             "ms_per_step", "ratio_peer_over_tumble", "tower_drift_60s_m", "max_penetration_m",
             "asleep_at_s", "sleeping_run_end_s", "note", "top_box_moved_m", "stands",
             "top_box_left_at_s"});
    for (std::size_t si = 0; si < m.scenes.size(); ++si) {
      const SceneResult& r = m.scenes[si];
      const std::vector<Row> rs = rows(m, r);
      for (std::size_t ei = 0; ei < rs.size(); ++ei) {
        const Row& row = rs[ei];
        const Behaviour& b = r.engine.at(row.engine).sleeping;
        out.row() << r.spec.name << si << row.engine << ei << r.bodies << r.timed_steps << row.ms
                  << row.ratio << row.tower_drift << row.penetration << b.asleep_at << b.end_time
                  << row.note << row.top_moved << row.stands << b.top_left_at;
        print(row);
      }
      record_scene(o, r, rs);
    }
  }
  return plot(o, "contact", plot_script(m));
}

}  // namespace tumble_bench::contact
