/// stages, measure: each scene stepped `steps` times per repetition, the stage times of
/// World::last_step() summed; scenes interleaved within a repetition.
#include <chrono>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "scenes.hpp"
#include "stages/stages.hpp"
#include "tumble/world.hpp"

namespace tumble_bench::stages {
namespace {

struct Spec {
  std::string label;
  std::function<tumble::Scene()> build;
  long steps;
  bool keep_awake;       // a zero impulse on every body every 15 steps, as in `contact`
  unsigned threads = 1;  // World::set_threads
};

std::vector<Spec> specs(bool quick) {
  const std::size_t n = quick ? 1000 : 10000;
  const std::string cubes = " (" + std::to_string(n) + " cubes)";
  return {{"tower", [] { return bundled("tower"); }, quick ? 60 : 600, true},
          {"pyramid", [] { return bundled("pyramid"); }, quick ? 10 : 60, true},
          {"pile", [] { return bundled("pile"); }, quick ? 10 : 120, true},
          {"pile (two threads)", [] { return bundled("pile"); }, quick ? 10 : 120, true, 2},
          {"throughput" + cubes,
           [n] { return separated_boxes(n, 1.0 / 240.0, 42, BoxShape::cube); },
           quick ? 60 : 480, false},
          {"landing" + cubes, [n] { return landing_cubes(n); }, quick ? 60 : 480, false}};
}

/// One repetition of one scene: totals in ns (wall, CPU, per stage, per contact-solve pass).
struct Totals {
  double wall_ns = 0.0, cpu_ns = 0.0;
  std::array<double, tumble::kStageCount> stage_ns{};
  std::array<double, tumble::kSolvePassCount> pass_ns{};
};

Totals run_once(const Spec& spec, const tumble::Scene& scene) {
  tumble::World w(scene);
  w.set_threads(spec.threads);
  w.set_stage_timing(true);  // off by default: two clock reads per stage
  Totals t;
  for (long i = 1; i <= spec.steps; ++i) {
    if (spec.keep_awake && i % 15 == 0)
      for (std::size_t b = 0; b < w.bodies().size(); ++b)
        w.apply_impulse(static_cast<tumble::BodyId>(b), tumble::Vec3::Zero());
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = thread_cpu_seconds();
    w.step();
    t.cpu_ns += (thread_cpu_seconds() - c0) * 1e9;
    t.wall_ns += std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0)
                     .count();
    for (int s = 0; s < tumble::kStageCount; ++s)
      t.stage_ns[s] += static_cast<double>(w.last_step().stage_ns[s]);
    for (int p = 0; p < tumble::kSolvePassCount; ++p)
      t.pass_ns[p] += static_cast<double>(w.last_step().solve_pass_ns[p]);
  }
  return t;
}

SceneStages summarize(const Spec& spec, std::size_t bodies, const std::vector<Totals>& runs) {
  SceneStages r{spec.label, bodies, spec.steps, spec.keep_awake};
  const double per_step_us = 1e-3 / static_cast<double>(spec.steps);
  std::vector<double> wall, cpu;
  for (const Totals& t : runs) {
    wall.push_back(t.wall_ns * per_step_us);
    cpu.push_back(t.cpu_ns * per_step_us);
  }
  r.step_us = median(wall);
  r.step_cpu_us = median(cpu);
  for (int s = 0; s < tumble::kStageCount; ++s) {
    std::vector<double> v;
    for (const Totals& t : runs) v.push_back(t.stage_ns[s] * per_step_us);
    r.stage_us[s] = median(v);
    r.stage_sum_us += r.stage_us[s];
  }
  for (int p = 0; p < tumble::kSolvePassCount; ++p) {
    std::vector<double> v;
    for (const Totals& t : runs) v.push_back(t.pass_ns[p] * per_step_us);
    r.pass_us[p] = median(v);
  }
  return r;
}

}  // namespace

Measurement measure(const Options& o) {
  Measurement m;
  m.reps = o.quick ? 1 : std::max(3, o.repeats);
  std::vector<Spec> all;
  for (const Spec& s : specs(o.quick))
    if (selected(o, s.label.substr(0, s.label.find(' ')))) all.push_back(s);
  if (all.empty())
    throw std::runtime_error("--only names none of tower, pyramid, pile, throughput, landing");
  std::vector<tumble::Scene> scenes;
  for (const Spec& s : all) scenes.push_back(s.build());
  std::vector<std::vector<Totals>> runs(all.size());
  Progress bar("stages", static_cast<std::size_t>(m.reps) * all.size());
  for (int r = 0; r < m.reps; ++r) {
    for (std::size_t i = 0; i < all.size(); ++i) {
      bar.note(all[i].label);
      runs[i].push_back(run_once(all[i], scenes[i]));
      bar.tick();
    }
  }
  for (std::size_t i = 0; i < all.size(); ++i) {
    m.scenes.push_back(summarize(all[i], scenes[i].bodies.size(), runs[i]));
    m.available = m.available || m.scenes.back().stage_sum_us > 0.0;
  }
  return m;
}

}  // namespace tumble_bench::stages
