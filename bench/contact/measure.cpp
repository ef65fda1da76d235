/// contact, measure: every scene on every engine; timings interleaved by repetition (each
/// repetition runs every engine in turn on a fresh world), then one untimed behaviour run per
/// engine. Returns plain structs; writes nothing.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "contact/contact.hpp"
#include "scenes.hpp"
#include "tumble/world.hpp"

namespace tumble_bench::contact {
namespace {

/// CPU seconds per step over `steps` steps of a fresh, kept-awake engine (building it is not
/// timed); stops early once `budget` CPU seconds are spent (*done: steps actually run;
/// *wall: wall-clock seconds per step of the same steps; *alone: of those, the steps run on
/// the calling thread alone, or -1).
double timed_awake(const Contender& c, const tumble::Scene& s, long steps, double budget,
                   long* done, double* wall, long* alone, std::string* why) {
  std::unique_ptr<PeerWorld> e;
  try {
    e = c.make(s, PeerSetup{.stacking = true, .allow_sleep = false});
  } catch (const std::exception& ex) {
    *why = ex.what();
    return NAN;
  }
  double cpu = 0.0, elapsed = 0.0;
  long i = 1;
  for (; i <= steps && cpu < budget; ++i) {
    const double t0 = clock_of(c);
    const auto w0 = std::chrono::steady_clock::now();
    e->keep_awake(i);
    e->step();
    elapsed += std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    cpu += clock_of(c) - t0;
  }
  *done = i - 1;
  *wall = elapsed / static_cast<double>(*done);
  *alone = e->steps_alone();
  const std::string t = e->trouble();
  if (!t.empty()) *why = t;
  return cpu / static_cast<double>(*done);
}

/// Index of the body that starts highest (the top of a stack).
std::size_t top_body(const tumble::Scene& s) {
  std::size_t top = 0;
  for (std::size_t i = 1; i < s.bodies.size(); ++i)
    if (s.bodies[i].position.y() > s.bodies[top].position.y()) top = i;
  return top;
}

/// One untimed run: kept awake for `steps` steps (`awake`), else sleeping as the engine does,
/// stopping once everything sleeps or after `budget` CPU seconds. Penetration sampled every
/// `every` steps; the top box followed every step.
Behaviour observe(const Contender& c, const tumble::Scene& s, long steps, bool awake, int every,
                  double budget) {
  Behaviour r;
  std::unique_ptr<PeerWorld> e;
  try {
    e = c.make(s, PeerSetup{.stacking = true, .allow_sleep = !awake});
  } catch (const std::exception& ex) {
    r.trouble = ex.what();
    return r;
  }
  std::vector<Vec3> x0;
  for (std::size_t i = 0; i < s.bodies.size(); ++i) x0.push_back(e->state(i).position);
  const std::size_t top = top_body(s);
  double deepest = 0.0, top_moved = 0.0;
  long i = 1;
  const double t0 = thread_cpu_seconds();
  for (; i <= steps && thread_cpu_seconds() - t0 <= budget; ++i) {
    if (awake) e->keep_awake(i);
    e->step();
    top_moved = std::max(top_moved, (e->state(top).position - x0[top]).norm());
    if (top_moved > kStandsTolerance && !std::isfinite(r.top_left_at))
      r.top_left_at = static_cast<double>(i) * s.world.dt;
    if (i % every == 0) deepest = std::max(deepest, deepest_penetration(*e, s));
    if (!awake && e->awake_count() == 0) {
      r.asleep_at = static_cast<double>(i) * s.world.dt;
      break;
    }
  }
  r.penetration = deepest;
  r.top_moved = top_moved;
  r.drift = 0.0;
  for (std::size_t k = 0; k < x0.size(); ++k)
    r.drift = std::max(r.drift, (e->state(k).position - x0[k]).norm());
  r.end_time = std::isfinite(r.asleep_at) ? r.asleep_at
                                          : static_cast<double>(std::min(i, steps + 1) - 1) *
                                                s.world.dt;
  r.trouble = e->trouble();
  return r;
}

/// Steps Tumble takes before any body sleeps (at most `cap`).
long steps_before_first_sleep(const tumble::Scene& s, long cap) {
  tumble::World w(s);
  for (long i = 1; i <= cap; ++i) {
    w.step();
    if (w.awake_count() < s.bodies.size()) return i - 1;
  }
  return cap;
}

/// One timed repetition of every engine on one scene.
void time_engines(const Measurement& m, const tumble::Scene& s, SceneResult& r, Progress& bar) {
  for (const Contender& c : m.engines) {
    EngineResult& e = r.engine[c.name];
    if (e.refused.rfind("MuJoCo 2.2 allocates", 0) == 0) continue;  // refused at build: always
    bar.note(r.spec.name + " " + c.name);
    std::string why;
    long done = 0, alone = -1;
    double wall = NAN;
    const double per_step =
        timed_awake(c, s, r.timed_steps, r.spec.budget, &done, &wall, &alone, &why);
    if (!why.empty()) e.refused = why;
    e.ms.push_back(per_step * 1e3);
    e.wall_ms.push_back(wall * 1e3);
    e.steps_done = e.ms.size() == 1 ? done : std::min(e.steps_done, done);
    e.steps_alone = std::max(e.steps_alone, alone);
  }
}

SceneResult measure_scene(const Measurement& m, const SceneSpec& spec, Progress& bar) {
  const tumble::Scene s = bundled(spec.name);
  SceneResult r;
  r.spec = spec;
  r.bodies = s.bodies.size();
  r.dt = s.world.dt;
  r.timed_steps = spec.fixed_timed_steps > 0 ? spec.fixed_timed_steps
                                             : steps_before_first_sleep(s, spec.timed_cap);
  r.timed_steps = std::max(1L, r.timed_steps);
  for (int rep = 0; rep < m.reps; ++rep) {
    time_engines(m, s, r, bar);
    bar.tick();
  }
  for (const Contender& c : m.engines) {
    EngineResult& e = r.engine[c.name];
    if (c.threads > 1) {  // bit-identical to one thread (tests/engine/threads_test.cpp)
      e.tower_awake = r.engine["tumble"].tower_awake;
      e.sleeping = r.engine["tumble"].sleeping;
      continue;
    }
    bar.note(spec.name + " " + c.name + " behaviour");
    if (spec.name == "tower")
      e.tower_awake = observe(c, s, m.tower_steps, true, 1, spec.behaviour_budget);
    e.sleeping = observe(c, s, spec.sleep_cap, false, spec.every, spec.behaviour_budget);
  }
  bar.tick();
  return r;
}

}  // namespace

long tower_awake_steps(bool quick) { return quick ? 60 : 3600; }

std::vector<SceneSpec> scene_specs(bool quick) {
  // Budgets: CPU seconds of one timed run and of one behaviour run. An engine that needs more
  // is timed over the steps it managed and its behaviour run ends early ("> t" in the table).
  // pyramid_large is timed over its first 30 steps (0.5 s: nothing can sleep before that) and
  // watched for 10 s; with --quick it only proves that it runs (a few steps). The pile is
  // timed over its first 180 steps (3 s: the fall and the pile-up): the steps before its first
  // sleep shrank to 26 (a box landing flat on the floor sleeps at once), mostly free fall.
  if (quick)
    return {{"tower", tower_awake_steps(true), 0, 60, 1, 0.5, 1.0, true},
            {"pyramid", 0, 20, 60, 1, 0.5, 1.0, true},
            {"pile", 0, 20, 20, 5, 0.5, 1.0, false},
            {"pyramid_large", 2, 0, 3, 1, 2.0, 4.0, true}};
  return {{"tower", tower_awake_steps(false), 0, 600, 1, 25.0, 40.0, true},
          {"pyramid", 0, 600, 600, 1, 25.0, 40.0, true},
          {"pile", 180, 0, 900, 5, 25.0, 40.0, false},
          {"pyramid_large", 30, 0, 600, 10, 60.0, 150.0, true}};
}

Measurement measure(const Options& o) {
  Measurement m;
  m.engines = contenders(false, o.threads);
  m.reps = o.quick ? 1 : std::max(3, o.repeats);
  m.tower_steps = tower_awake_steps(o.quick);
  std::vector<SceneSpec> specs;
  for (const SceneSpec& s : scene_specs(o.quick))
    if (selected(o, s.name)) specs.push_back(s);
  if (specs.empty())
    throw std::runtime_error("--only names none of tower, pyramid, pile, pyramid_large");
  Progress bar("contact", specs.size() * (static_cast<std::size_t>(m.reps) + 1));
  for (const SceneSpec& spec : specs) m.scenes.push_back(measure_scene(m, spec, bar));
  return m;
}

}  // namespace tumble_bench::contact
