// The active-set solve of simultaneous normal impulses (active_set.hpp): rank decisions that
// do not depend on units, and bounded impulses for points that lie almost on one line.
#include <algorithm>
#include <random>

#include <Eigen/SVD>

#include <gtest/gtest.h>

#include "active_set.hpp"

namespace tumble {
namespace {

/// A 1 kg unit cube seen from its bottom face's centre (0.5 m below its centre of mass).
ContactSide unit_cube_side() {
  ContactSide side;
  side.inv_mass = 1.0;
  side.inv_inertia = Mat3::Identity() * 6.0;  // I = m (1² + 1²) / 12 = 1/6 kg·m²
  side.origin_offset = Vec3(0.0, -0.5, 0.0);
  return side;
}

/// Impulses that stop the points of `offsets` (on the cube's bottom face, floor held fixed)
/// approaching at `speeds` m/s.
PointVector stop(const std::vector<Vec3>& offsets, const std::vector<double>& speeds) {
  const ContactSide cube = unit_cube_side();
  const int n = static_cast<int>(offsets.size());
  const NormalSystem sys = make_normal_system(Vec3::UnitY(), Vec3::UnitX(), Vec3::UnitZ(),
                                              offsets.data(), n, nullptr, &cube);
  ActiveSetCache cache(sys);
  PointVector vn(n);
  for (int i = 0; i < n; ++i) vn(i) = -speeds[i];
  return solve_active_set(cache, vn, PointVector::Zero(n));
}

// Three points a few µm off one line across a 1 m face, as two merged support patches of one
// box give. The line runs along the face's edge, 0.5 m off its centre: stopping it (the box
// free to tip about it) takes Δv / (1/m + 0.5² / I) = 6e-4 / 2.5 N·s in all, shared between
// points that all push.
TEST(ActiveSet, PointsAlmostOnOneLineGetImpulsesOfTheRightSize) {
  const std::vector<Vec3> offsets{{0.5, 0.0, 0.0248}, {0.5, 0.0, 0.5}, {0.49996, 0.0, -0.5}};
  // The speeds differ by a few per cent, as the unconverged iterations left them.
  const PointVector j = stop(offsets, {6.03e-4, 6.23e-4, 5.80e-4});
  EXPECT_NEAR(j.sum(), 6e-4 / 2.5, 1e-5);
  EXPECT_GE(j.minCoeff(), 0.0);
  EXPECT_LT(j.maxCoeff(), 6e-4);
}

// The rank test is scale-free: a 1 mm square patch is a square, and its four corners share
// the load of a uniform approach equally, as a 1 m patch's do.
TEST(ActiveSet, SmallAndLargePatchesShareTheLoadAlike) {
  for (const double h : {0.5, 5e-4}) {
    ContactSide cube = unit_cube_side();
    const std::vector<Vec3> offsets{{h, 0, h}, {-h, 0, h}, {-h, 0, -h}, {h, 0, -h}};
    const NormalSystem sys = make_normal_system(Vec3::UnitY(), Vec3::UnitX(), Vec3::UnitZ(),
                                                offsets.data(), 4, nullptr, &cube);
    ActiveSetCache cache(sys);
    const PointVector j = solve_active_set(cache, PointVector::Constant(4, -1.0),
                                           PointVector::Zero(4));
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(j(i), 0.25, 1e-12) << "half size " << h;
  }
}

/// K⁺ of K = D S Dᵀ through D P Dᵀ, against a long-double SVD pseudo-inverse of the m×m K; the
/// largest entry difference relative to K⁺'s largest entry.
double pseudo_inverse_error(const std::vector<Vec3>& offsets, const Vec3& normal) {
  ContactSide cube = unit_cube_side();
  cube.inv_inertia = Vec3(5.0, 7.0, 3.0).asDiagonal();  // unequal axes: S with every term
  Vec3 t1, t2;
  tangents(normal, t1, t2);
  const int n = static_cast<int>(offsets.size());
  const NormalSystem sys =
      make_normal_system(normal, t1, t2, offsets.data(), n, nullptr, &cube);
  // The reference in long double: K's condition number reaches ~1e7 for a 1 mm patch.
  using MatL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  const MatL Dl = sys.D.cast<long double>();
  const MatL K = Dl * sys.S.cast<long double>() * Dl.transpose();
  const Eigen::JacobiSVD<MatL> svd(K, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix<long double, Eigen::Dynamic, 1> inv_sigma = svd.singularValues();
  for (Eigen::Index i = 0; i < inv_sigma.size(); ++i)
    inv_sigma(i) = inv_sigma(i) > 1e-12L * svd.singularValues()(0) ? 1.0L / inv_sigma(i) : 0.0L;
  const Eigen::MatrixXd want =
      (svd.matrixV() * inv_sigma.asDiagonal() * svd.matrixU().transpose()).cast<double>();
  const Eigen::MatrixXd D = sys.D;
  const Eigen::MatrixXd got = D * pseudo_inverse_factor(sys.D, sys.S) * D.transpose();
  return (got - want).cwiseAbs().maxCoeff() / want.cwiseAbs().maxCoeff();
}

// Points on one line (an edge against a face) and a single point give G = DᵀD of rank two
// and one: the factor is built on G's range without an eigendecomposition, and D P Dᵀ is still
// the pseudo-inverse of K, at any tilt of the line and any size of the patch (the
// eigendecomposition this replaced was 3e-11 off for the 1 mm edge).
TEST(ActiveSet, PointsOnOneLineAndSinglePointsGetThePseudoInverse) {
  const Vec3 normal = Vec3(0.3, 1.0, -0.2).normalized();
  const Vec3 along = normal.cross(Vec3(0.7, 0.1, 0.4)).normalized();
  for (const double size : {1.0, 1e-3}) {
    const Vec3 base = size * Vec3(0.2, -0.1, 0.3);
    const std::vector<std::vector<Vec3>> cases{
        {base, base + size * along},                                           // an edge
        {base, base + 0.3 * size * along, base - 0.9 * size * along},          // three on it
        {base, base + 0.5 * size * along, base, base + 0.5 * size * along},    // repeated
        {base},                                                                // a corner
        {Vec3::Zero()},                                                        // at the origin
        {base, base}};                                                         // one, twice
    for (std::size_t c = 0; c < cases.size(); ++c)
      EXPECT_LT(pseudo_inverse_error(cases[c], normal), 1e-12) << "case " << c << ", " << size;
  }
}

// A single point is solved without the loop (solve_active_set's first branch): its impulse is
// the one the loop's single solve gives through the rank-one pseudo-inverse factor, bit for bit,
// for any body, lever and approach, and zero where the point does not approach its target.
TEST(ActiveSet, OnePointGetsTheGeneralSolvesImpulseToTheBit) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 normal = Vec3{u(rng), u(rng), u(rng)}.normalized();
    Vec3 t1, t2;
    tangents(normal, t1, t2);
    const Mat3 A = Mat3::Random() + 2.0 * Mat3::Identity();
    ContactSide side;
    side.inv_mass = 0.1 + std::abs(u(rng));
    side.inv_inertia = A * A.transpose();  // symmetric positive definite
    side.origin_offset = 0.7 * Vec3{u(rng), u(rng), u(rng)};
    const Vec3 offset = Vec3::Zero();  // one point is its own origin
    const NormalSystem sys = make_normal_system(normal, t1, t2, &offset, 1, nullptr, &side);
    ActiveSetCache cache(sys);
    PointVector vn(1), target(1);
    vn(0) = 3.0 * u(rng);
    target(0) = trial % 3 == 0 ? 0.0 : 2.0 * u(rng);
    const double got = solve_active_set(cache, vn, target)(0);
    // The loop's one solve: y = D_aᵀ (target − vn), z = P y, j = d · z.
    double want = 0.0;
    if (vn(0) < target(0) - 1e-15) {
      Vec3 y = Vec3::Zero();
      add_row(y, target(0) - vn(0), sys.D, 0);
      want = row_dot(sys.D, 0, pseudo_inverse_factor(sys.D, sys.S) * y);
    }
    ASSERT_EQ(got, want) << "trial " << trial;
  }
}

}  // namespace
}  // namespace tumble
