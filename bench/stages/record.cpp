/// stages, record: stages.csv (one row per scene, one column per stage and per contact-solve
/// pass) and headline values.
#include <iostream>

#include "report.hpp"
#include "stages/stages.hpp"

namespace tumble_bench::stages {
namespace {

/// "tower", "throughput", … : the scene label up to the first space.
std::string key_of(const SceneStages& s) { return s.scene.substr(0, s.scene.find(' ')); }

}  // namespace

fs::path record(const Options& o, const Measurement& m) {
  const fs::path path = o.out / "stages.csv";
  std::vector<std::string> columns{"scene", "bodies", "steps", "kept_awake", "step_wall_us",
                                   "step_cpu_us", "stage_sum_us"};
  for (int s = 0; s < tumble::kStageCount; ++s)
    columns.push_back(std::string(tumble::stage_name(static_cast<tumble::Stage>(s))) + "_us");
  for (int p = 0; p < tumble::kSolvePassCount; ++p)
    columns.push_back("solve_" +
                      std::string(tumble::solve_pass_name(static_cast<tumble::SolvePass>(p))) +
                      "_us");
  Csv out(path, columns);
  for (const SceneStages& r : m.scenes) {
    out.row() << r.scene << r.bodies << r.steps << (r.kept_awake ? 1 : 0) << r.step_us
              << r.step_cpu_us << r.stage_sum_us;
    for (double us : r.stage_us) out << us;
    for (double us : r.pass_us) out << us;
    std::cerr << "  " << r.scene << ": " << fmt(r.step_us) << " µs per step (wall), stages sum "
              << fmt(r.stage_sum_us) << " µs\n";
    const std::string k = "stages." + key_of(r) + ".";
    record_value(o, k + "step_us", fmt(r.step_us, 4));
    record_value(o, k + "stage_sum_us", fmt(r.stage_sum_us, 4));
  }
  record_value(o, "stages.available", m.available ? "yes" : "no");
  return path;
}

}  // namespace tumble_bench::stages
