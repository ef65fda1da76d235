/// The event-driven reference of the `seed` scene (see seed_reference in work_precision.hpp).
#include <boost/math/tools/toms748_solve.hpp>

#include <algorithm>

#include "tumble_reference/free_rigid_body.hpp"
#include "work_precision/work_precision.hpp"

namespace tumble_bench::wp {
namespace {

namespace ref = tumble_reference;
using tumble::Mat3;
using tumble::Vec3;

constexpr double kScan = 1e-3;  // s between sign checks of the lowest-vertex height

/// The first grid time after t (capped at t_end) at which the lowest vertex is below the
/// floor (*hi, with the last time above it in *lo); false when there is none.
bool first_crossing(const SeedReference& s, const tumble::Body& b, const Vec3& gravity, double t,
                    double t_end, double tol, double* lo, double* hi) {
  std::vector<double> grid;
  for (double tau = kScan; t + tau < t_end + kScan; tau += kScan)
    grid.push_back(std::min(tau, t_end - t));
  const auto Rs = ref::free_rigid_body_attitudes(b.c.inertia, s.R, s.L, grid,
                                                 ref::Method::kQuaternionRkf78, tol);
  *lo = 0.0;
  for (std::size_t k = 0; k < grid.size(); ++k) {
    const Vec3 x = s.x + s.v * grid[k] + 0.5 * gravity * grid[k] * grid[k];
    if (x.y() - Rs[k].row(1).cwiseAbs().dot(b.c.half_extents) < 0.0) {
      *hi = grid[k];
      return true;
    }
    *lo = grid[k];
  }
  return false;
}

/// Frictionless single-vertex impulse at the lowest vertex, applied to s.
void apply_impact(SeedReference& s, const tumble::Body& b, double e) {
  int lowest = 0;
  double ymin = INFINITY;
  for (int i = 0; i < 8; ++i) {
    const Vec3 r = s.R * tumble::body_vertex(b.c, i);
    if (r.y() < ymin) {
      ymin = r.y();
      lowest = i;
    }
  }
  const Vec3 r = s.R * tumble::body_vertex(b.c, lowest);
  const Mat3 inv_I = s.R * b.c.inertia.cwiseInverse().asDiagonal() * s.R.transpose();
  const Vec3 n(0.0, 1.0, 0.0);
  const Vec3 omega = inv_I * s.L;
  const double vn = n.dot(s.v + omega.cross(r));
  const double j = -(1.0 + e) * vn / (b.c.inv_mass + n.dot((inv_I * r.cross(n)).cross(r)));
  s.v += j * b.c.inv_mass * n;
  s.L += r.cross(j * n);
  ++s.impacts;
}

}  // namespace

SeedReference seed_reference(const tumble::Body& b, const Vec3& gravity, double e, double t_end,
                             double tol) {
  SeedReference s{b.s.x, b.s.P * b.c.inv_mass, b.s.L, b.s.R, 0};
  // Moves s along its flight by tau (exact parabola, reference attitude).
  auto advance = [&](double tau) {
    if (tau != 0.0)
      s.R = ref::free_rigid_body_attitude(b.c.inertia, s.R, s.L, tau,
                                          ref::Method::kQuaternionRkf78, tol);
    s.x = s.x + s.v * tau + 0.5 * gravity * tau * tau;
    s.v += gravity * tau;
  };
  auto height = [&](double tau) {
    const Mat3 R = tau == 0.0 ? s.R
                              : ref::free_rigid_body_attitude(b.c.inertia, s.R, s.L, tau,
                                                              ref::Method::kQuaternionRkf78, tol);
    const Vec3 x = s.x + s.v * tau + 0.5 * gravity * tau * tau;
    return x.y() - R.row(1).cwiseAbs().dot(b.c.half_extents);
  };
  double t = 0.0;
  while (t < t_end) {
    double lo = 0.0, hi = 0.0;
    if (!first_crossing(s, b, gravity, t, t_end, tol, &lo, &hi)) {
      advance(t_end - t);  // no impact before t_end
      return s;
    }
    std::uintmax_t iters = 200;
    const auto root = boost::math::tools::toms748_solve(
        height, lo, hi, boost::math::tools::eps_tolerance<double>(52), iters);
    const double tc = 0.5 * (root.first + root.second);
    advance(tc);
    t += tc;
    apply_impact(s, b, e);
  }
  return s;
}

}  // namespace tumble_bench::wp
