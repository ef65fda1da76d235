/// stages, report: the `stages` section, bench/text/stages.md filled in. When every stage time
/// is zero (an engine build that does not fill StepStats::stage_ns) it says so instead of
/// printing a table of zeros.
#include <cmath>

#include "report.hpp"
#include "stages/stages.hpp"
#include "text.hpp"

namespace tumble_bench::stages {
namespace {

std::string scenes_table(const Measurement& m) {
  std::vector<std::vector<std::string>> rows;
  for (const SceneStages& s : m.scenes)
    rows.push_back({s.scene, std::to_string(s.bodies), std::to_string(s.steps),
                    s.kept_awake ? "yes" : "no", fmt(s.step_us), fmt(s.step_cpu_us)});
  return md_table({"scene", "bodies", "steps", "kept awake", "µs per step (wall)",
                   "µs per step (CPU)"},
                  rows);
}

/// "12.3 (45 %)": µs per step and share of the measured step.
std::string cell(double us, double step_us) {
  return fmt(us) + " (" + fixed(100.0 * us / step_us, 1) + " %)";
}

std::string stage_table(const Measurement& m) {
  if (!m.available)
    return "**stage timings not available in this engine build** (every "
           "`StepStats::stage_ns` is zero), so there is no per-stage table.\n";
  std::vector<std::string> header{"stage"};
  for (const SceneStages& s : m.scenes) header.push_back(s.scene + ": µs per step (%)");
  std::vector<std::vector<std::string>> rows;
  for (int st = 0; st < tumble::kStageCount; ++st) {
    std::vector<std::string> row{
        "`" + std::string(tumble::stage_name(static_cast<tumble::Stage>(st))) + "`"};
    for (const SceneStages& s : m.scenes) row.push_back(cell(s.stage_us[st], s.step_us));
    rows.push_back(row);
  }
  std::vector<std::string> sum{"sum of the stages"}, step{"measured step (wall)"},
      outside{"outside any stage"};
  for (const SceneStages& s : m.scenes) {
    sum.push_back(cell(s.stage_sum_us, s.step_us));
    step.push_back(fmt(s.step_us) + " (100 %)");
    outside.push_back(cell(s.step_us - s.stage_sum_us, s.step_us));
  }
  rows.push_back(sum);
  rows.push_back(step);
  rows.push_back(outside);
  return "Per stage, µs per step and its share of the measured step:\n\n" +
         md_table(header, rows);
}

/// The contact solve's passes, for the scenes that have contacts to solve.
std::string pass_table(const Measurement& m) {
  if (!m.available) return "";
  const int solve = static_cast<int>(tumble::Stage::contact_solve);
  std::vector<const SceneStages*> solved;
  for (const SceneStages& s : m.scenes)
    if (s.stage_us[solve] > 0.0 && s.stage_us[solve] >= 0.05 * s.step_us) solved.push_back(&s);
  if (solved.empty()) return "";
  std::vector<std::string> header{"pass of `contact_solve`"};
  for (const SceneStages* s : solved) header.push_back(s->scene + ": µs per step (%)");
  std::vector<std::vector<std::string>> rows;
  for (int p = 0; p < tumble::kSolvePassCount; ++p) {
    std::vector<std::string> row{
        "`" + std::string(tumble::solve_pass_name(static_cast<tumble::SolvePass>(p))) + "`"};
    for (const SceneStages* s : solved) row.push_back(cell(s->pass_us[p], s->step_us));
    rows.push_back(row);
  }
  std::vector<std::string> stage{"the whole stage"};
  for (const SceneStages* s : solved) stage.push_back(cell(s->stage_us[solve], s->step_us));
  rows.push_back(stage);
  return "The contact solve's passes (`tumble::SolvePass`, timed into "
         "`StepStats::solve_pass_ns`), in the scenes where the stage takes 5 % of the step "
         "or more; µs per step and share of the measured step:\n\n" +
         md_table(header, rows);
}

}  // namespace

void report(const Options& o, const Measurement& m, const fs::path& csv) {
  const auto v = recorded_values(o);
  const Fields f{
      {"date", v.count("date") ? v.at("date") : "unknown"},
      {"engine_commit", v.count("engine_commit") ? v.at("engine_commit") : "unknown"},
      {"quick", o.quick ? " --quick" : ""},
      {"partial", partial_note(o)},
      {"reps", std::to_string(m.reps)},
      {"csv", file_link(o, csv)},
      {"scenes_table", scenes_table(m)},
      {"stage_table", stage_table(m)},
      {"pass_table", pass_table(m)},
  };
  write_section(o, "stages", fill_template("stages", f));
}

}  // namespace tumble_bench::stages
