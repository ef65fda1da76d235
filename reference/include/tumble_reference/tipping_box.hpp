#pragma once
/// Reference solution of a box tipping over one of its edges, for tests and benchmarks.
///
/// A box whose edge rests on the floor and neither slides nor leaves it rotates about that
/// edge as an inverted pendulum: I_e θ̈ = m g d sin θ, θ the angle of the centre of mass from
/// the vertical through the edge, d the centre's distance from the edge and I_e the moment of
/// inertia about the edge (a unit cube: d = √2/2, I_e = 2m/3, so θ̈ = 1.5 g d sin θ).
/// Integrated with Boost.Odeint (Dormand–Prince 5(4), dense output, abs = rel = 1e-14) from
/// rest at θ0, each crossing time found by bisection on the dense output.
/// Usage: auto t = tumble_reference::tipping_times(1.5 * 9.81 * std::sqrt(0.5), 0.05, {0.2});
/// Pure function of its arguments; thread-safe. Header-only.
#include <array>
#include <cmath>
#include <vector>

#include <boost/numeric/odeint.hpp>

namespace tumble_reference {

/// Times (s) at which θ, starting at rest from theta0 > 0 (rad) under θ̈ = rate2 sin θ
/// (rate2 = m g d / I_e, 1/s²), first reaches each of `angles` (ascending, each > theta0 and
/// below π/2).
inline std::vector<double> tipping_times(double rate2, double theta0,
                                         const std::vector<double>& angles) {
  namespace odeint = boost::numeric::odeint;
  using State = std::array<double, 2>;  // θ, θ̇
  const auto rhs = [rate2](const State& x, State& dx, double) {
    dx[0] = x[1];
    dx[1] = rate2 * std::sin(x[0]);
  };
  auto stepper = odeint::make_dense_output(1e-14, 1e-14, odeint::runge_kutta_dopri5<State>());
  stepper.initialize(State{theta0, 0.0}, 0.0, 1e-4);
  std::vector<double> times;
  while (times.size() < angles.size()) {
    const auto [t0, t1] = stepper.do_step(rhs);
    State x;
    while (times.size() < angles.size()) {
      const double target = angles[times.size()];
      stepper.calc_state(t1, x);
      if (x[0] < target) break;
      double lo = t0, hi = t1;
      for (int k = 0; k < 80; ++k) {
        const double mid = 0.5 * (lo + hi);
        stepper.calc_state(mid, x);
        (x[0] < target ? lo : hi) = mid;
      }
      times.push_back(0.5 * (lo + hi));
    }
  }
  return times;
}

}  // namespace tumble_reference
