#pragma once
/// Simultaneous normal impulses at up to kMaxPoints contact points by an active-set solve,
/// shared by the floor contacts and the box–box contacts. Pure functions; thread-safe.
#include <array>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace tumble {

/// Most contact points one solve handles.
inline constexpr int kMaxActiveSetPoints = 8;

/// A K matrix (normal velocity change at i per unit impulse at j) of a few contact points.
using PointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxActiveSetPoints,
                                  kMaxActiveSetPoints>;
/// Per-point values (velocities, targets, impulses).
using PointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxActiveSetPoints, 1>;

/// K⁺ of a symmetric positive semi-definite K, dropping eigenvalues below 1e-12 of the
/// largest (the null space of a flat face's four contacts).
inline PointMatrix pseudo_inverse(const PointMatrix& K) {
  const Eigen::Index m = K.rows();
  if (m == 1) return PointMatrix::Constant(1, 1, 1.0 / K(0, 0));
  Eigen::SelfAdjointEigenSolver<PointMatrix> eig(K);
  const PointVector lambda = eig.eigenvalues();
  const double cutoff = 1e-12 * lambda.cwiseAbs().maxCoeff();
  PointVector inv(m);
  for (Eigen::Index a = 0; a < m; ++a) inv(a) = std::abs(lambda(a)) > cutoff ? 1.0 / lambda(a) : 0.0;
  return eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
}

/// Pseudo-inverses of the sub-matrices of one K met so far, keyed by the active set: within
/// one impulse exchange K is fixed, so repeated solves (friction rounds) reuse them.
class ActiveSetCache {
 public:
  explicit ActiveSetCache(const PointMatrix& K) : K_(K) {}
  /// The matrix solved.
  const PointMatrix& K() const { return K_; }
  /// K⁺ restricted to the points in `mask` (bit i = point i), listed in idx[0..m).
  const PointMatrix& inverse(unsigned mask, const std::array<int, kMaxActiveSetPoints>& idx,
                             int m) {
    for (int c = 0; c < cached_; ++c)
      if (masks_[c] == mask) return inverses_[c];
    PointMatrix Ka(m, m);
    for (int a = 0; a < m; ++a)
      for (int b = 0; b < m; ++b) Ka(a, b) = K_(idx[a], idx[b]);
    const int slot = cached_ < kCache ? cached_++ : (next_++ % kCache);
    masks_[slot] = mask;
    inverses_[slot] = pseudo_inverse(Ka);
    return inverses_[slot];
  }

 private:
  static constexpr int kCache = 4;
  PointMatrix K_;
  int cached_ = 0, next_ = 0;
  std::array<unsigned, kCache> masks_{};
  std::array<PointMatrix, kCache> inverses_;
};

// Simultaneous normal impulses by an active-set solve (Baraff 1989, "Analytical methods for
// dynamic simulation of non-penetrating rigid bodies", §4, with equality targets): every
// active point leaves with v⁺ₙ = targetᵢ and a non-negative impulse; a point that would pull
// is dropped, a passive one that would approach faster than its target is added. K is
// singular for four coplanar points (a face has three normal degrees of freedom), so each
// solve uses the pseudo-inverse; rigid-body targets are then consistent and a flat landing
// stays flat. With e = 1 every active point reverses its normal velocity, which conserves
// kinetic energy exactly: ΔT = Σ jᵢ (v⁻ᵢ + v⁺ᵢ)/2 = 0.
/// Impulses (≥ 0) for points with normal velocities vn and targets; K from `cache`.
inline PointVector solve_active_set(ActiveSetCache& cache, const PointVector& vn,
                                    const PointVector& target) {
  const int n = static_cast<int>(vn.size());
  const PointMatrix& K = cache.K();
  std::array<bool, kMaxActiveSetPoints> active{};
  for (int i = 0; i < n; ++i) active[i] = vn(i) < target(i) - 1e-15;
  PointVector impulse = PointVector::Zero(n);
  for (int iter = 0; iter < 4 * kMaxActiveSetPoints; ++iter) {
    std::array<int, kMaxActiveSetPoints> idx{};
    int m = 0;
    unsigned mask = 0;
    for (int i = 0; i < n; ++i)
      if (active[i]) idx[m++] = i, mask |= 1u << i;
    impulse.setZero();
    if (m > 0) {
      PointVector b(m);
      for (int a = 0; a < m; ++a) b(a) = target(idx[a]) - vn(idx[a]);
      const PointVector ja = cache.inverse(mask, idx, m) * b;
      for (int a = 0; a < m; ++a) impulse(idx[a]) = ja(a);
    }
    // Drop the most negative impulse, else add the most violated passive point.
    int worst = -1;
    double worst_value = -1e-14;
    for (int i = 0; i < n; ++i)
      if (active[i] && impulse(i) < worst_value) worst = i, worst_value = impulse(i);
    if (worst >= 0) {
      active[worst] = false;
      continue;
    }
    const PointVector after = vn + K * impulse;
    worst_value = -1e-12;
    for (int i = 0; i < n; ++i)
      if (!active[i] && after(i) - target(i) < worst_value)
        worst = i, worst_value = after(i) - target(i);
    if (worst < 0) break;
    active[worst] = true;
  }
  return impulse;
}

}  // namespace tumble
