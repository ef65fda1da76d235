#include "landing/landing.hpp"

#include <cmath>

#include "common.hpp"

namespace tumble_bench::landing {
namespace {

/// Steps (untimed) until every box is asleep or `steps` more steps; returns the sim time when
/// they all slept (NaN if not) and leaves *watched at the time covered.
double settle(PeerWorld& w, long done, long steps, double dt, double* watched) {
  for (long i = 1; i <= steps; ++i) {
    w.step();
    if (w.awake_count() == 0) {
      *watched = static_cast<double>(done + i) * dt;
      return *watched;
    }
  }
  *watched = static_cast<double>(done + steps) * dt;
  return NAN;
}

}  // namespace

Plan plan(bool quick) {
  if (quick) return {120, 60, 0};  // 0.5 s (most boxes land), first 0.25 s
  return {480, 120, 960};  // 2 s timed, then up to 4 s more to see every box asleep
}

double watched_until(const Plan& p, double dt) {
  return static_cast<double>(p.steps + p.settle_steps) * dt;
}

std::vector<std::size_t> sizes(bool quick) {
  return quick ? std::vector<std::size_t>{100, 1000} : std::vector<std::size_t>{1000, 10000};
}

Run run(const Contender& c, const tumble::Scene& s, const Plan& p, bool settle_after) {
  Run r;
  std::unique_ptr<PeerWorld> w;
  try {
    w = c.make(s, PeerSetup{});
  } catch (const std::exception& e) {
    r.trouble = e.what();
    return r;
  }
  const double n = static_cast<double>(s.bodies.size());
  const long long impacts0 = w->impacts();
  // awake_count() walks the bodies in some engines: read it outside the timed part.
  double cpu = 0.0, head_cpu = 0.0;
  for (long i = 1; i <= p.steps; ++i) {
    const double t0 = thread_cpu_seconds();
    w->step();
    cpu += thread_cpu_seconds() - t0;
    if (i == p.head_steps) head_cpu = cpu;
    if (c.sleeps && !std::isfinite(r.all_asleep_at) && w->awake_count() == 0)
      r.all_asleep_at = static_cast<double>(i) * s.world.dt;
  }
  r.ns_per_body_step = cpu * 1e9 / (n * static_cast<double>(p.steps));
  r.ns_per_body_step_head = head_cpu * 1e9 / (n * static_cast<double>(p.head_steps));
  if (impacts0 >= 0) r.impacts_per_box = static_cast<double>(w->impacts() - impacts0) / n;
  const long awake = w->awake_count();
  if (c.sleeps && awake >= 0) r.asleep_fraction = 1.0 - static_cast<double>(awake) / n;
  r.watched_until = static_cast<double>(p.steps) * s.world.dt;
  if (c.sleeps && awake > 0 && settle_after && p.settle_steps > 0)
    r.all_asleep_at = settle(*w, p.steps, p.settle_steps, s.world.dt, &r.watched_until);
  r.trouble = w->trouble();
  return r;
}

}  // namespace tumble_bench::landing
