/// pile-precision, measure: `pile` on every engine at every step size, penetration after every
/// step (the same 15-axis depth as `contact`), only the stepping timed. Writes nothing.
#include <algorithm>
#include <cmath>
#include <exception>

#include "contact/contact.hpp"
#include "contenders.hpp"
#include "pile_precision/pile_precision.hpp"
#include "scenes.hpp"

namespace tumble_bench::pile_precision {
namespace {

/// One run of `s` for `steps` steps, with the engine's own sleeping, as a user runs it.
Point run(const Contender& c, const tumble::Scene& s, long steps, double budget) {
  Point p;
  p.engine = c.name;
  p.dt = s.world.dt;
  std::unique_ptr<PeerWorld> w;
  try {
    w = c.make(s, PeerSetup{.stacking = true, .allow_sleep = true});
  } catch (const std::exception& e) {
    p.trouble = e.what();
    p.cpu_per_sim_s = p.deepest = p.deepest_at = p.time_over = NAN;
    return p;
  }
  double cpu = 0.0;
  for (long i = 1; i <= steps && cpu < budget; ++i) {
    const double t0 = clock_of(c);
    w->step();
    cpu += clock_of(c) - t0;
    p.steps = i;
    const double depth = contact::deepest_penetration(*w, s);
    if (depth > kBound) p.time_over += s.world.dt;
    if (depth > p.deepest) {
      p.deepest = depth;
      p.deepest_at = static_cast<double>(i) * s.world.dt;
    }
  }
  p.cpu_per_sim_s = cpu / (static_cast<double>(p.steps) * s.world.dt);
  p.trouble = w->trouble();
  return p;
}

/// The engines in table order: Tumble, Tumble with the scene's overlap bound at kBound
/// (WorldDef::max_overlap), then the peers.
std::vector<Contender> engines_with_bound() {
  std::vector<Contender> engines = contenders();
  Contender bounded = engines.front();
  bounded.name = kBoundedName;
  bounded.make = [plain = engines.front().make](const tumble::Scene& s, const PeerSetup& setup) {
    tumble::Scene with_bound = s;
    with_bound.world.max_overlap = kBound;
    return plain(with_bound, setup);
  };
  engines.insert(engines.begin() + 1, bounded);
  return engines;
}

}  // namespace

Measurement measure(const Options& o) {
  Measurement m;
  // The fall and the pile-up: at dt = 1/60 every step deeper than 1 cm comes before 3.7 s.
  m.duration = o.quick ? 0.5 : 4.0;
  m.budget = o.quick ? 5.0 : 60.0;
  m.dts = o.quick ? std::vector<double>{1.0 / 60, 1.0 / 120}
                  : std::vector<double>{1.0 / 60, 1.0 / 120, 1.0 / 240, 1.0 / 480};
  const tumble::Scene pile = bundled("pile");
  const std::vector<Contender> engines = engines_with_bound();
  for (const Contender& c : engines) m.engines.push_back(c.name);
  m.initial = contact::deepest_penetration(*engines.front().make(pile, {}), pile);
  Progress bar("pile-precision", m.dts.size() * engines.size());
  for (const double dt : m.dts) {
    tumble::Scene s = pile;
    s.world.dt = dt;
    const long steps = std::lround(m.duration / dt);
    for (const Contender& c : engines) {
      bar.note(c.name + " dt = " + dt_label(dt));
      m.points.push_back(run(c, s, steps, m.budget));
      bar.tick();
    }
  }
  return m;
}

double cpu_at_depth(const Measurement& m, const std::string& engine, double depth,
                    bool* at_most) {
  *at_most = false;
  const Point* before = nullptr;  // the engine at the previous (larger) dt
  for (const Point& p : m.points) {
    if (p.engine != engine || !std::isfinite(p.cpu_per_sim_s)) continue;
    if (p.deepest <= depth) {
      if (!before) {
        *at_most = true;
        return p.cpu_per_sim_s;
      }
      const double f = std::log(before->deepest / depth) / std::log(before->deepest / p.deepest);
      return before->cpu_per_sim_s * std::pow(p.cpu_per_sim_s / before->cpu_per_sim_s, f);
    }
    before = &p;
  }
  return NAN;
}

}  // namespace tumble_bench::pile_precision
