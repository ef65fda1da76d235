#include "floor_time_of_impact.hpp"

#include <boost/math/tools/toms748_solve.hpp>

#include "hermite_root.hpp"
#include "integrators.hpp"

namespace tumble::floor_detail {
namespace {

// Of the step: how far before the secant's root the closing evaluation goes (1e-15 of the step
// let round-off in the heights turn it down at times). The narrowest bracket tried around the
// guess is kGuessRoundOff (hermite_root.hpp): a body that does not turn, whose guess is exact
// but for round-off.
constexpr double kClosingOffset = 1e-14;

/// Fourth time derivative of the height of a point at offset r (world) on a body turning at ω
/// about a fixed axis: |ω|⁴ times r's component normal to ω, its y (m/s⁴).
double turn_fourth_derivative_y(const Vec3& w, const Vec3& r) {
  const double w2 = w.squaredNorm();
  return w2 * (w2 * r.y() - r.dot(w) * w.y());
}

/// A first guess at the time of impact and how far it may be off.
struct ImpactGuess {
  double time = 0.0;   ///< s, in (0, h]; h when no vertex ends below the floor.
  double error = 0.0;  ///< Bound on |time − the impact's time|, s.
};

/// The guess of time_of_impact: the earliest root among the vertices of `mask` that end below
/// the floor, each from the cubic Hermite interpolant of its height and vertical speed at both
/// ends of the step (states s and end), plus its leading error term. The error bound is the
/// cubic's alone, generous for the quartic: a cubic Hermite interpolant over h is off by at
/// most h⁴/384 max|y⁗|; the centre's height is a parabola (y⁗ = 0) and a vertex's turn about
/// it has |y⁗| ≤ 16 Ω⁴ r, where Ω² = 2E / I_min bounds |ω|² in torque-free motion (E the
/// rotational energy; 16 a generous constant for the derivatives of ω a general body adds),
/// divided by the speed at the root; never below kGuessRoundOff h, near the evaluations' own
/// round-off. The bound only sets the bracket tried first, which evaluations then check.
ImpactGuess hermite_time_of_impact(const BodyState& s, const BodyState& end,
                                   const BodyConstants& c, double floor_y, double h,
                                   unsigned mask) {
  const HalfEdges e0(s, c), e1(end, c);
  const Vec3 v0 = c.inv_mass * s.P, v1 = c.inv_mass * end.P;
  const Vec3 w0 = angular_velocity(s, c), w1 = angular_velocity(end, c);
  const double h2 = h * h;
  double earliest = 1.0, speed = 0.0;
  for (int i = 0; i < 8; ++i) {
    if (!(mask & (1u << i))) continue;
    const double y1 = end.x.y() + e1.vertex_y(i) - floor_y;
    const double y0 = s.x.y() + e0.vertex_y(i) - floor_y;
    if (y1 >= 0.0 || y0 <= 0.0) continue;
    const Vec3 r0 = e0.vertex(i), r1 = e1.vertex(i);
    const double d0 = h * vertex_speed_y(v0, w0, r0);
    const double d1 = h * vertex_speed_y(v1, w1, r1);
    // The cubic's error y⁗ h⁴ τ²(τ − 1)² / 24 with the turn's y⁗ (the mean of both ends):
    // without it one spinning cube's guess in five came late by more than the tolerance (the
    // lowest vertex's y⁗ is negative: the true height lies below the cubic).
    const double y4 =
        0.5 * (turn_fourth_derivative_y(w0, r0) + turn_fourth_derivative_y(w1, r1));
    const HermiteRoot root = hermite_root(y0, d0, y1, d1, y4 * h2 * h2 / 24.0);
    if (root.tau < earliest) earliest = root.tau, speed = std::abs(root.slope) / h;
  }
  if (speed == 0.0) return {h, INFINITY};  // no vertex of the mask ends below the floor
  const double omega2 = w0.dot(s.L) * c.inv_inertia.maxCoeff();  // 2E / I_min ≥ |ω|²
  const double y4_bound = 16.0 * omega2 * omega2 * c.bounding_radius;
  const double h4 = h * h * h * h;
  const double error = h4 / 384.0 * y4_bound / speed;
  return {earliest * h, std::max(error, kGuessRoundOff * h)};
}

}  // namespace

/// Earliest time in [0, h] at which a vertex of `mask` reaches the floor (it is above at 0
/// and some vertex of the mask is below at h, in the state `end`). Returns the non-penetrating
/// end of the final bracket, so a body is never left inside the floor, and sets `at` to the
/// body's state then.
///
/// Both searches end on a time they evaluated with the body above the floor (the lower end of
/// the bracket), so that evaluation's state is kept rather than computed again: the latest
/// time evaluated above the floor is that end. One trajectory evaluation saved per impact,
/// the same bits.
double time_of_impact(const BodyState& s, const BodyState& end, const BodyConstants& c,
                      const WorldDef& w, double floor_y, double h, unsigned mask,
                      double height_at_h, int& evaluations, BodyState& at) {
  double at_t = 0.0;
  at = s;
  auto height_of = [&](const BodyState& st) {
    return (mask == 0xFF ? lowest_vertex_y(st, c) : lowest_masked_y(st, c, mask)) - floor_y;
  };
  auto height = [&](double t) {
    ++evaluations;
    const BodyState st = advance(w.integrator, s, c, w.gravity, t);
    const double y = height_of(st);
    if (y >= 0.0 && t > at_t) at_t = t, at = st;
    return y;
  };
  auto state_at = [&](double t) {
    if (t != at_t) at = advance(w.integrator, s, c, w.gravity, t);  // not met: kept for safety
    return t;
  };
  if (w.toi == ToiMethod::bisection) {
    // The seed's search: halve the interval, keeping the last time that does not penetrate.
    double lo = 0.0, hi = h;
    while (hi - lo > w.toi_tolerance) {
      const double mid = 0.5 * (lo + hi);
      (height(mid) < 0.0 ? hi : lo) = mid;
    }
    return state_at(lo);
  }
  const double tol = w.toi_tolerance;
  // Why a guess first: both ends of the step are known states, and each vertex's height and
  // vertical speed there fix its cubic Hermite interpolant (hermite_time_of_impact). Two
  // evaluations, at its root ± its error bound (at most tol/2), then bracket the impact;
  // TOMS 748 took 4.1–4.4 an impact in the landings of cubes and general boxes. When they do
  // not (the lowest vertex changes within the step, a tolerance below the guess's error), the
  // one that failed narrows the bracket TOMS 748 starts from.
  double lo = 0.0, hi = h, y_lo = height_of(s), y_hi = height_at_h;
  const ImpactGuess guess = hermite_time_of_impact(s, end, c, floor_y, h, mask);
  const double offset = kClosingOffset * h;
  const double half_width = std::min(guess.error, 0.45 * tol);
  const double a = guess.time - half_width, b = guess.time + half_width;
  if (a > 0.0 && b < h) {
    const double ya = height(a);
    if (ya < 0.0) {
      hi = a, y_hi = ya;
    } else {
      const double yb = height(b);
      if (yb < 0.0) {
        // A bracket wider than round-off (a spinning body's, up to the tolerance) is closed by
        // its secant, exact to ~(b − a)² y''/y' ≈ 1e-18 s, and one evaluation just before it:
        // the time comes out to round-off. The seed scene ends 1.2e-11 m from its reference
        // so, 2e-7 m with TOMS 748 alone (its last bracket anywhere inside the tolerance) and
        // 1e-6 m with the guess's bracket unclosed.
        const double closer = a + (b - a) * (ya / (ya - yb)) - offset;
        if (half_width > offset && closer > a && height(closer) >= 0.0)
          return state_at(closer);
        return state_at(a);
      }
      lo = b, y_lo = yb;
    }
  }
  // TOMS 748 (Alefeld, Potra & Shi 1995) on the lowest-vertex height along the trajectory:
  // cubic inverse interpolation with bracketing, a few evaluations where bisection takes
  // log2(h / tolerance). The lower end keeps the sign of height(lo) ≥ 0. The step's start is
  // s itself: its height needs no trajectory evaluation (advancing by 0 s gives s back to the
  // bit).
  std::uintmax_t max_iter = 100;
  const auto bracket = boost::math::tools::toms748_solve(
      height, lo, hi, y_lo, y_hi, [tol](double x, double y) { return y - x <= tol; }, max_iter);
  return state_at(bracket.first);
}

}  // namespace tumble::floor_detail
