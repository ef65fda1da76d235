#include "friction_rounds.hpp"

#include <Eigen/QR>

namespace tumble::floor_detail {

RoundOutput FrictionRounds::operator()(const RoundInput& in) const {
  BodyState s;
  Kinematics k;
  const Impulses normal = apply(in, s, k);
  return read(in, normal, k);
}

// Newton's method on f(x) = G(x) − x, with f's Jacobian by forward differences (six rounds)
// and a step halved until |f| falls. G is smooth between its kinks, so near a fixed point
// that is not on one a step takes the residual from 1e-5 to round-off, where the rounds gain
// a factor of two or three each. On a kink the differences straddle it and Newton stalls;
// resolve then goes on with plain rounds, which creep in, and `best` keeps whichever round
// came closest.
// Measured on the 3,000 sliding edges of the friction tests and a 1,000-cube landing at
// μ = 1 (docs/engine-log.md, "What changed").
void polish(const FrictionRounds& rounds, double lever, ClosestRound& best) {
  constexpr int kSteps = 3;      // Newton steps at most
  constexpr int kHalvings = 4;   // tries of each step, halved each time
  constexpr double kDiff = 1e-7;  // the differences' step, relative to the unknown's scale
  RoundVector x = round_vector(best.output, lever);
  RoundOutput out = rounds(best.output);
  if (out.limit <= 0.0) return;
  RoundVector f = round_vector(out.next, lever) - x;
  for (int step = 0; step < kSteps; ++step) {
    Eigen::Matrix<double, 6, 6> jacobian;
    for (int i = 0; i < 6; ++i) {
      const double scale = i < 3 ? out.limit : lever;  // N·s for F and τ / r, m for c
      const double h = kDiff * std::max(std::abs(x(i)), scale);
      RoundVector xi = x;
      xi(i) += h;
      const RoundOutput oi = rounds(round_input(xi, lever));
      if (oi.limit <= 0.0) return;
      jacobian.col(i) = (round_vector(oi.next, lever) - xi - f) / h;
    }
    const RoundVector dx = jacobian.colPivHouseholderQr().solve(-f);
    bool fell = false;
    double t = 1.0;
    for (int k = 0; k < kHalvings && !fell; ++k, t *= 0.5) {
      const RoundVector xt = x + t * dx;
      const RoundOutput ot = rounds(round_input(xt, lever));
      if (ot.limit <= 0.0) continue;
      const RoundVector ft = round_vector(ot.next, lever) - xt;
      if (ft.squaredNorm() >= f.squaredNorm()) continue;
      x = xt, f = ft, out = ot, fell = true;
    }
    if (!fell) return;
    const double residual = round_residual(round_input(x, lever), out.next, lever);
    if (residual < best.residual) best = {residual, out.next, out.limit};
    if (residual <= 1e-13 * out.limit) return;
  }
}

}  // namespace tumble::floor_detail
