/// throughput, measure: the scaling sweep (cubes and boxes alternating), every integrator at
/// one N, and the landing runs of Tumble. Returns plain structs; writes nothing.
#include <algorithm>
#include <cmath>

#include "throughput/throughput.hpp"
#include "tumble/world.hpp"

namespace tumble_bench::throughput {
namespace {

/// One timed run. The first `head_steps` steps (the fall, before most impacts) are timed
/// apart from the rest, so that every N can be compared over the same simulated interval.
Run run_once(const tumble::Scene& scene, long steps, long head_steps) {
  reset_peak_resident();
  const double before = static_cast<double>(resident_bytes());
  tumble::World w(scene);
  const double built = static_cast<double>(resident_bytes());
  double awake = 0.0, head_cpu = 0.0;
  const double t0 = thread_cpu_seconds();
  for (long i = 0; i < steps; ++i) {
    w.step();
    awake += w.last_step().awake;
    if (i + 1 == head_steps) head_cpu = thread_cpu_seconds() - t0;
  }
  const double cpu = thread_cpu_seconds() - t0;
  const double peak = static_cast<double>(peak_resident_bytes());
  const double n = static_cast<double>(scene.bodies.size());
  return {cpu * 1e9 / (n * static_cast<double>(steps)),
          head_cpu * 1e9 / (n * static_cast<double>(head_steps)),
          awake / (n * static_cast<double>(steps)),
          std::max(peak, static_cast<double>(resident_bytes())) / 1e6,
          std::max(0.0, built - before) / n};
}

void measure_scaling(Measurement& m, Progress& bar) {
  const Config& c = m.cfg;
  for (std::size_t n : c.sizes) {
    bar.note("N = " + std::to_string(n));
    const long s_n = n >= c.n_big ? c.head_steps : c.steps;
    // Small N: repeat until about 2e6 body-steps, so each size costs about the same.
    const long wanted = std::min<long>(50, 2000000 / (static_cast<long>(n) * s_n) + 1);
    const int r_n = n >= c.n_big ? 1 : std::max(c.reps, static_cast<int>(wanted));
    const std::array<tumble::Scene, 2> scenes{separated_boxes(n, kDt, 42, kShapes[0]),
                                              separated_boxes(n, kDt, 42, kShapes[1])};
    for (int r = 0; r < r_n; ++r)
      for (std::size_t k = 0; k < kShapes.size(); ++k)
        m.scaling[{kShapes[k], n}].push_back(run_once(scenes[k], s_n, c.head_steps));
    bar.tick();
  }
}

void measure_integrators(Measurement& m, Progress& bar) {
  const Config& c = m.cfg;
  std::vector<std::pair<BoxShape, tumble::Scene>> scenes;
  for (BoxShape shape : kShapes) scenes.push_back({shape, separated_boxes(c.n_integ, kDt, 42, shape)});
  for (int r = 0; r < c.reps; ++r) {
    for (tumble::Integrator integ : tumble::kIntegrators) {
      bar.note(std::string(tumble::to_string(integ)));
      for (auto& [shape, scene] : scenes) {
        scene.world.integrator = integ;
        m.by_integrator[{shape, integ}].push_back(
            run_once(scene, c.steps, c.head_steps).ns_per_body_step);
      }
    }
    bar.tick();
  }
}

/// Tumble on the landing scenes; sizes interleaved within each repetition.
void measure_landing(Measurement& m, Progress& bar) {
  const Contender tumble = contenders().front();
  std::vector<tumble::Scene> scenes;
  for (std::size_t n : m.cfg.landing_sizes) scenes.push_back(landing_cubes(n));
  for (int r = 0; r < m.cfg.reps; ++r) {
    for (const tumble::Scene& s : scenes) {
      bar.note("landing N = " + std::to_string(s.bodies.size()));
      m.landing[s.bodies.size()].push_back(landing::run(tumble, s, m.cfg.landing, r == 0));
    }
    bar.tick();
  }
}

}  // namespace

Config config(const Options& o) {
  Config c;
  c.sizes = o.quick ? std::vector<std::size_t>{1, 100, 1000}
                    : std::vector<std::size_t>{1, 100, 1000, 10000, 100000};
  c.duration = o.quick ? 0.25 : 2.0;
  c.steps = std::lround(c.duration / kDt);
  // The largest N is run for the first 0.5 s only (the whole 2 s of the general boxes would
  // take over a minute per run); every N is also timed over those same first steps.
  c.head_duration = o.quick ? 0.125 : 0.5;
  c.head_steps = std::lround(c.head_duration / kDt);
  c.n_integ = o.quick ? 1000 : 10000;
  c.reps = o.repeats;
  c.landing = landing::plan(o.quick);
  c.landing_sizes = landing::sizes(o.quick);
  return c;
}

Measurement measure(const Options& o) {
  Measurement m;
  m.cfg = config(o);
  Progress bar("throughput", m.cfg.sizes.size() + 2 * static_cast<std::size_t>(m.cfg.reps));
  measure_scaling(m, bar);
  measure_integrators(m, bar);
  measure_landing(m, bar);
  return m;
}

}  // namespace tumble_bench::throughput
