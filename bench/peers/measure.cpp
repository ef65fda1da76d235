/// peers, measure: every part on every engine, engines interleaved within each repetition.
/// Returns plain structs; writes nothing.
#include <cmath>

#include "peers/peers.hpp"
#include "tumble/world.hpp"
#include "tumble_reference/free_rigid_body.hpp"

namespace tumble_bench::peers {
namespace {

constexpr double kDt = 1.0 / 240.0;
constexpr BoxShape kShapes[] = {BoxShape::cube, BoxShape::general};

/// `tumble` at dt = 1/15 · 2^-k on every engine: orientation error after 20 s against the
/// same reference solution.
void measure_tumble(Measurement& m, Progress& bar) {
  const tumble::Scene scene = bundled("tumble");
  const tumble::World probe(scene);
  const tumble::Body& b0 = probe.body(0);
  const double duration = 20.0;
  const tumble::Mat3 R_ref =
      tumble_reference::free_rigid_body_attitude(b0.c.inertia, b0.s.R, b0.s.L, duration);
  for (const Contender& c : m.all) {
    bar.note("tumble " + c.name);
    for (int k = 0; k < m.tumble_dts; ++k) {
      tumble::Scene s = scene;
      s.world.dt = 1.0 / (15.0 * std::pow(2.0, k));
      std::unique_ptr<PeerWorld> w;
      const double cpu = timed_run(c, s, std::lround(duration / s.world.dt), &w);
      const double err = w ? tumble::rotation_angle_between(
                                 R_ref, w->state(0).orientation.toRotationMatrix())
                           : NAN;
      m.tumble.push_back({c.name, s.world.dt, cpu, err});
    }
    bar.tick();
  }
}

/// Apexes of one engine: y + v²/2g of the last rising state before each descent.
BounceRun bounce_once(const Contender& c, const tumble::Scene& s, double half) {
  BounceRun r{c.name};
  const double g0 = -s.world.gravity.y();
  auto w = c.make(s, PeerSetup{});
  int found = 0;
  bool rising = false;
  double prev = 0.0;
  for (int i = 0; i < 180 && found < 3; ++i) {
    w->step();
    const PeerBodyState st = w->state(0);
    // Lowest point of a (nearly) flat cube: centre minus the half height along y.
    const double y = st.position.y() - half * std::fabs((st.orientation * Vec3::UnitY()).y());
    const double vy = st.velocity.y();
    if (vy > 0.0) {
      rising = true;
      prev = y + vy * vy / (2.0 * g0);
    } else if (rising) {
      r.apex[found++] = prev;
      rising = false;
    }
  }
  return r;
}

void measure_bounce(Measurement& m, Progress& bar) {
  tumble::Scene s = bundled("bounce");
  s.world.dt = 1.0 / 60.0;
  const tumble::World probe(s);
  const double half = probe.body(0).c.half_extents.y();
  m.bounce_h0 = probe.body(0).s.x.y() - half;
  m.bounce_e = s.world.floor->restitution;
  for (const Contender& c : m.all) {
    bar.note("bounce " + c.name);
    BounceRun r = bounce_once(c, s, half);
    r.err = std::fabs(r.apex[0] - m.bounce_e * m.bounce_e * m.bounce_h0);
    m.bounce.push_back(r);
    bar.tick();
  }
}

/// One repetition of every engine on every throughput scene, then on the skip scene.
void throughput_rep(Measurement& m, const std::map<Key, tumble::Scene>& scenes,
                    const tumble::Scene& skip, Progress& bar) {
  for (const auto& [key, s] : scenes) {
    const std::string label = "N=" + std::to_string(key.first) + " " + to_string(key.second);
    for (const Contender& c : m.fast) {
      if (m.refused.count(c.name + " " + label)) continue;  // refuses every time: don't retry
      bar.note(label + " " + c.name);
      std::string why;
      const double cpu = timed_run(c, s, m.steps, nullptr, &why);
      if (!why.empty()) m.refused[c.name + " " + label] = why;
      m.ns[c.name][key].push_back(cpu * 1e9 / (static_cast<double>(key.first) * m.steps));
    }
    bar.tick();
  }
  for (const Contender& c : m.fast) {
    bar.note("skip " + c.name);
    std::string why;
    const double cpu = timed_run(c, skip, m.skip_steps, nullptr, &why);
    if (!why.empty()) m.refused[c.name + " skip"] = why;
    m.skip_ms[c.name].push_back(cpu * 1e3 / static_cast<double>(m.skip_steps));
  }
  bar.tick();
}

/// One repetition of every engine on every landing scene; the first also looks past the
/// timed run for the moment every box sleeps.
void landing_rep(Measurement& m, const std::vector<tumble::Scene>& scenes, int rep,
                 Progress& bar) {
  for (const tumble::Scene& s : scenes) {
    const std::size_t n = s.bodies.size();
    for (const Contender& c : m.fast) {
      std::vector<landing::Run>& runs = m.landing[c.name][n];
      if (!runs.empty() && runs.front().trouble.rfind("MuJoCo 2.2 allocates", 0) == 0) continue;
      bar.note("landing N=" + std::to_string(n) + " " + c.name);
      runs.push_back(landing::run(c, s, m.landing_plan, rep == 0));
    }
  }
  bar.tick();
}

}  // namespace

Measurement measure(const Options& o) {
  Measurement m;
  m.all = contenders(true);
  m.fast = contenders(false);
  m.reps = o.quick ? 1 : std::max(3, o.repeats);
  m.tumble_dts = o.quick ? 4 : 9;
  m.sizes = o.quick ? std::vector<std::size_t>{100, 1000} : std::vector<std::size_t>{1000, 10000};
  m.duration = o.quick ? 0.25 : 2.0;
  m.steps = std::lround(m.duration / kDt);
  m.resting = o.quick ? 1000 : 10000;
  m.skip_steps = o.quick ? 30 : 120;
  m.landing_plan = landing::plan(o.quick);
  m.landing_sizes = landing::sizes(o.quick);
  const auto reps = static_cast<std::size_t>(m.reps);
  Progress bar("peers", m.all.size() * 2 + reps * (m.sizes.size() * 2 + 2));
  measure_tumble(m, bar);
  measure_bounce(m, bar);
  std::map<Key, tumble::Scene> scenes;
  for (std::size_t n : m.sizes)
    for (BoxShape shape : kShapes) scenes[{n, shape}] = separated_boxes(n, kDt, 42, shape);
  const tumble::Scene skip = resting_and_falling(m.resting, 10);
  for (int r = 0; r < m.reps; ++r) throughput_rep(m, scenes, skip, bar);
  std::vector<tumble::Scene> landings;
  for (std::size_t n : m.landing_sizes) landings.push_back(landing_cubes(n));
  for (int r = 0; r < m.reps; ++r) landing_rep(m, landings, r, bar);
  return m;
}

}  // namespace tumble_bench::peers
