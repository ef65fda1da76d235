#pragma once
/// Simultaneous normal impulses at up to kMaxPoints contact points by an active-set solve,
/// shared by the floor contacts and the box–box contacts. Pure functions; thread-safe.
#include <array>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/LU>

#include "tumble/math.hpp"

namespace tumble {

/// Most contact points one solve handles.
inline constexpr int kMaxActiveSetPoints = 8;

/// Per-point values (velocities, targets, impulses).
using PointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxActiveSetPoints, 1>;

/// Rows (1, α, β) of contact points: α, β their coordinates in the contact plane, m. The leading
/// 1 is exactly 1.0 (gram, row_dot and add_row leave its products out).
using PlaneCoordinates =
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor, kMaxActiveSetPoints, 3>;

/// Two unit tangents completing n to a right-handed basis, chosen the same way every step so
/// accumulated friction impulses stay meaningful for warm starting.
inline void tangents(const Vec3& n, Vec3& t1, Vec3& t2) {
  const Vec3 ref = std::abs(n.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  t1 = n.cross(ref).normalized();
  t2 = n.cross(t1);
}

/// One side of a contact seen by the normal impulses: a body (or nothing, for the floor).
struct ContactSide {
  double inv_mass = 0.0;            ///< 1/kg.
  Mat3 inv_inertia = Mat3::Zero();  ///< World I⁻¹, 1/(kg·m²).
  Vec3 origin_offset = Vec3::Zero();///< The plane's origin minus the body's centre, m.
};

// The normal-impulse matrix of points that share one normal n has rank three at most:
// Kᵢⱼ = Σ_sides m⁻¹ + (rᵢ × n)ᵀ I⁻¹ (rⱼ × n), and rᵢ × n depends on the point only through its
// two coordinates (αᵢ, βᵢ) in the plane normal to n (the component along n drops out of the
// cross product). So K = D S Dᵀ with D's rows dᵢ = (1, αᵢ, βᵢ) and S a 3×3 matrix (the
// effective inverse mass of the patch's normal force and its two tipping moments). Its
// pseudo-inverse follows in closed form from 3×3 algebra: for D of full column rank,
// K⁺ = D G⁻¹ S⁻¹ G⁻¹ Dᵀ with G = DᵀD (write D = QR: K = Q (R S Rᵀ) Qᵀ). This replaces the
// eigendecomposition of the m×m K (m up to 8) that used to dominate the contact solve.
/// The normal-impulse system K = D S Dᵀ of points sharing one normal (K itself is never
/// formed: every product with it goes through D and S).
struct NormalSystem {
  PlaneCoordinates D;     ///< (1, α, β) of each point.
  Mat3 S = Mat3::Zero();  ///< Patch inverse mass in those coordinates, 1/kg.
};

/// The system of points at `offsets` from a common plane origin (world vectors, m), normal n,
/// between sides `a` and `b` (null: held fixed, as the floor is). t1, t2 span the plane.
inline NormalSystem make_normal_system(const Vec3& n, const Vec3& t1, const Vec3& t2,
                                       const Vec3* offsets, int count, const ContactSide* a,
                                       const ContactSide* b) {
  NormalSystem sys;
  sys.D.resize(count, 3);
  for (int i = 0; i < count; ++i) sys.D.row(i) << 1.0, offsets[i].dot(t1), offsets[i].dot(t2);
  const Vec3 e1 = t1.cross(n), e2 = t2.cross(n);
  for (const ContactSide* side : {a, b}) {
    if (!side) continue;
    Mat3 C;
    C << side->origin_offset.cross(n), e1, e2;
    sys.S += C.transpose() * side->inv_inertia * C;
    sys.S(0, 0) += side->inv_mass;
  }
  return sys;
}

/// V H⁻¹ (Vᵀ S V)⁻¹ H⁻¹ Vᵀ with H = Vᵀ G V, for V's R orthonormal columns (R = 1, 2) spanning
/// the range kept of G: P of pseudo_inverse_factor_of_gram on that range, whatever the basis.
template <int R>
Mat3 reduced_pseudo_inverse(const Eigen::Matrix<double, 3, R>& V, const Mat3& G, const Mat3& S) {
  const Eigen::Matrix<double, R, R> H = V.transpose() * G * V;
  const Eigen::Matrix<double, R, R> T = V.transpose() * S * V;
  const Eigen::Matrix<double, 3, R> W = V * H.inverse();
  return W * T.inverse() * W.transpose();
}

// G⁻¹ in the operations of Eigen's 3×3 inverse (the cofactors, det G from the first column's,
// its reciprocal), whose det G also serves the rank test, which used to compute it a second
// time by G.determinant() (by the first row). For a G symmetric to the bit (gram_of_sums) the
// two are the same bits: their three terms are the same products, the middle one negated
// (a − b = −(b − a) exactly), except where that cofactor's two products are equal; then they
// can differ only in the sign of a zero, which fails the test (bound ≥ 0) either way.
/// True, with Gi = G⁻¹, when det G > bound (≥ 0); G symmetric (gram_of_sums).
inline bool inverse_above(const Mat3& G, double bound, Mat3& Gi) {
  const Vec3 c0(G(1, 1) * G(2, 2) - G(1, 2) * G(2, 1), G(2, 1) * G(0, 2) - G(2, 2) * G(0, 1),
                G(0, 1) * G(1, 2) - G(0, 2) * G(1, 1));  // column 0 of the cofactor matrix
  const double det = c0.cwiseProduct(G.col(0)).sum();
  if (!(det > bound)) return false;
  const double inv = 1.0 / det;
  Gi << c0(0) * inv, c0(1) * inv, c0(2) * inv,
      (G(1, 2) * G(2, 0) - G(1, 0) * G(2, 2)) * inv, (G(2, 2) * G(0, 0) - G(2, 0) * G(0, 2)) * inv,
      (G(0, 2) * G(1, 0) - G(0, 0) * G(1, 2)) * inv,
      (G(1, 0) * G(2, 1) - G(1, 1) * G(2, 0)) * inv, (G(2, 0) * G(0, 1) - G(2, 1) * G(0, 0)) * inv,
      (G(0, 0) * G(1, 1) - G(0, 1) * G(1, 0)) * inv;
  return true;
}

/// P with K⁺ = D P Dᵀ for K = D S Dᵀ (S symmetric positive definite): closed form when the
/// points span the plane; else on the range of D's Gram matrix G = DᵀD with its columns scaled
/// to unit length, a plane (points on one line) or a line (one point).
//
// Both tests are scale-free: det G / (G₀₀ G₁₁ G₂₂) is the Gram determinant of D's normalised
// columns (1 for orthogonal columns, 0 for collinear points), and the rank test below reads
// the same normalised matrix, so neither depends on the unit of length or the size of the
// box. The bound 1e-6 treats points within about 1e-3 of the patch's size of one line as on
// it. A looser bound (1e-10, which this replaced) let three points 40 µm off one edge of a
// 1 m face pass as spanning the plane; the inverse of that nearly singular G then gave
// impulses of 1,500 N·s to a 1 kg box.
//
// Below full rank, P = G⁺ X G⁺ with X = V (Vᵀ S V)⁻¹ Vᵀ for any orthonormal basis V of G's
// range (write G = V H Vᵀ: then D P Dᵀ = K⁺). That basis needs no eigendecomposition: for G of
// rank two, the cross product of two of its columns is normal to its range (each column lies
// in it); for rank one, any non-zero column spans it. Eigen's iterative 3×3 eigensolver, which
// this replaced, cost ~1,300 instructions a call and 6 % of all of `pile`'s (points on one
// edge are common there); this costs a few hundred.
inline Mat3 pseudo_inverse_factor_of_gram(const Mat3& G, const Mat3& S) {
  constexpr double kRank = 1e-6;
  Mat3 Gi;
  if (inverse_above(G, kRank * G(0, 0) * G(1, 1) * G(2, 2), Gi)) return Gi * S.inverse() * Gi;
  // D = D̂ N⁻¹ with D̂'s columns of unit length (N = diag(1/√Gₖₖ); a zero column stays zero),
  // so K = D̂ Ŝ D̂ᵀ with Ŝ = N⁻¹ S N⁻¹, and P = N P̂ N.
  Vec3 norm, inv_norm;
  for (int k = 0; k < 3; ++k) {
    norm(k) = std::sqrt(G(k, k));
    inv_norm(k) = norm(k) > 0.0 ? 1.0 / norm(k) : 0.0;
  }
  const Mat3 Gn = inv_norm.asDiagonal() * G * inv_norm.asDiagonal();
  const Mat3 Sn = norm.asDiagonal() * S * norm.asDiagonal();
  // Rank two when the largest column cross product, whose length lies between λ₁λ₂/√3 and
  // λ₁λ₂ (λ₁ ≥ λ₂ ≥ 0 the eigenvalues kept; the trace is λ₁ to 2λ₁), exceeds 1e-6 of the
  // trace squared: λ₂ above 1e-6 to 7e-6 of λ₁.
  const Vec3 cross[3] = {Gn.col(1).cross(Gn.col(2)), Gn.col(2).cross(Gn.col(0)),
                         Gn.col(0).cross(Gn.col(1))};
  int k = 0;
  for (int j = 1; j < 3; ++j)
    if (cross[j].squaredNorm() > cross[k].squaredNorm()) k = j;
  const double trace = Gn.trace();
  Mat3 Pn;
  if (cross[k].norm() > kRank * trace * trace) {
    Vec3 t1, t2;  // the range: the plane normal to the cross product
    tangents(cross[k].normalized(), t1, t2);
    Eigen::Matrix<double, 3, 2> V;
    V << t1, t2;
    Pn = reduced_pseudo_inverse<2>(V, Gn, Sn);
  } else {
    int j = 0;
    for (int i = 1; i < 3; ++i)
      if (Gn.col(i).squaredNorm() > Gn.col(j).squaredNorm()) j = i;
    if (!(Gn.col(j).squaredNorm() > 0.0)) return Mat3::Zero();
    Pn = reduced_pseudo_inverse<1>(Gn.col(j).normalized(), Gn, Sn);
  }
  return inv_norm.asDiagonal() * Pn * inv_norm.asDiagonal();
}

/// The Gram matrix of rows (1, αᵢ, βᵢ) from its five sums Σα, Σβ, Σα², Σαβ, Σβ² (and the count
/// m = Σ 1·1), mirrored: αβ = βα, so the lower triangle is the upper one to the bit.
inline Mat3 gram_of_sums(int m, double a, double b, double aa, double ab, double bb) {
  Mat3 G;
  G << m, a, b, a, aa, ab, b, ab, bb;
  return G;
}

/// G = Σ dᵢ dᵢᵀ over the rows listed in idx[0..m), summed in that order (the sums of
/// gram_of_sums; dᵢ's leading 1 makes its products exact, so they are left out).
inline Mat3 gram(const PlaneCoordinates& D, const int* idx, int m) {
  double a = 0.0, b = 0.0, aa = 0.0, ab = 0.0, bb = 0.0;
  for (int k = 0; k < m; ++k) {
    const double alpha = D(idx[k], 1), beta = D(idx[k], 2);
    a += alpha;
    b += beta;
    aa += alpha * alpha;
    ab += alpha * beta;
    bb += beta * beta;
  }
  return gram_of_sums(m, a, b, aa, ab, bb);
}

/// (1, α, β) · v over row i of D, as the dot product sums it: the leading 1's product is v₀.
inline double row_dot(const PlaneCoordinates& D, int i, const Vec3& v) {
  return (v(0) + D(i, 1) * v(1)) + D(i, 2) * v(2);
}

/// acc += s (1, α, β) over row i of D (the leading 1's product is s).
inline void add_row(Vec3& acc, double s, const PlaneCoordinates& D, int i) {
  acc(0) += s;
  acc(1) += s * D(i, 1);
  acc(2) += s * D(i, 2);
}

/// P with K⁺ = D P Dᵀ over all rows of D.
inline Mat3 pseudo_inverse_factor(const PlaneCoordinates& D, const Mat3& S) {
  std::array<int, kMaxActiveSetPoints> all{};
  for (int i = 0; i < D.rows(); ++i) all[i] = i;
  return pseudo_inverse_factor_of_gram(gram(D, all.data(), static_cast<int>(D.rows())), S);
}

/// Pseudo-inverse factors of the sub-systems of one K met so far, keyed by the active set:
/// within one impulse exchange K is fixed, so repeated solves (friction rounds) reuse them.
class ActiveSetCache {
 public:
  explicit ActiveSetCache(const NormalSystem& system) : system_(system) {}
  /// It keeps a reference: a temporary system would dangle.
  explicit ActiveSetCache(NormalSystem&&) = delete;
  /// The system solved.
  const NormalSystem& system() const { return system_; }
  /// P with (K restricted to the points in `mask`)⁺ = D_a P D_aᵀ; the points are idx[0..m).
  const Mat3& factor(unsigned mask, const std::array<int, kMaxActiveSetPoints>& idx, int m) {
    for (int c = 0; c < cached_; ++c)
      if (masks_[c] == mask) return factors_[c];
    const int slot = cached_ < kCache ? cached_++ : (next_++ % kCache);
    masks_[slot] = mask;
    factors_[slot] = pseudo_inverse_factor_of_gram(gram(system_.D, idx.data(), m), system_.S);
    return factors_[slot];
  }

 private:
  static constexpr int kCache = 4;
  const NormalSystem& system_;
  int cached_ = 0, next_ = 0;
  std::array<unsigned, kCache> masks_{};
  std::array<Mat3, kCache> factors_;
};

// Simultaneous normal impulses by an active-set solve (Baraff 1989, "Analytical methods for
// dynamic simulation of non-penetrating rigid bodies", §4, with equality targets): every
// active point leaves with v⁺ₙ = targetᵢ and a non-negative impulse; a point that would pull
// is dropped, a passive one that would approach faster than its target is added. K is
// singular for four coplanar points (a face has three normal degrees of freedom), so each
// solve uses the pseudo-inverse; rigid-body targets are then consistent and a flat landing
// stays flat. With e = 1 every active point reverses its normal velocity, which conserves
// kinetic energy exactly: ΔT = Σ jᵢ (v⁻ᵢ + v⁺ᵢ)/2 = 0.
//
// An iteration depends on nothing but its active set (the impulses are found afresh from it),
// so once an active set comes back the solve repeats itself with that period until the
// iteration limit, and returns the impulses of the limit's last iteration. Round-off can make
// it cycle so: in 30 steps of `pyramid` 226 of 6,174 solves ran all 32 iterations, half of all
// the iterations. On a repeat the count jumps ahead by whole periods, so the last iteration
// (and the result) is the one the full loop ends with.
/// Impulses (≥ 0) for points with normal velocities vn and targets; the system from `cache`.
inline PointVector solve_active_set(ActiveSetCache& cache, const PointVector& vn,
                                    const PointVector& target) {
  constexpr int kIterations = 4 * kMaxActiveSetPoints;
  const int n = static_cast<int>(vn.size());
  const PlaneCoordinates& D = cache.system().D;
  // One point, its own origin (D's row (1, 0, 0)): the loop below ends after one solve with
  // the factor P₀₀ = 1 / S₀₀ that the rank-one pseudo-inverse comes to (every other entry
  // zero), so the impulse is found here, to the bit, without that factor's rank search.
  // Tumbling boxes meet the floor on one corner in most impacts: 225,000 of the 299,000
  // floor solves of 10,000 cubes landing on a frictionless floor over 2 s.
  const double s00 = cache.system().S(0, 0);
  if (n == 1 && D(0, 1) == 0.0 && D(0, 2) == 0.0 && s00 > 0.0) {
    PointVector impulse = PointVector::Zero(1);
    if (vn(0) < target(0) - 1e-15) impulse(0) = (1.0 / s00) * (target(0) - vn(0));
    return impulse;
  }
  std::array<bool, kMaxActiveSetPoints> active{};
  std::array<double, kMaxActiveSetPoints> gap;  // target − vn
  for (int i = 0; i < n; ++i) {
    active[i] = vn(i) < target(i) - 1e-15;
    gap[i] = target(i) - vn(i);
  }
  PointVector impulse(n);  // zeroed by each iteration
  std::array<unsigned, kIterations> seen;  // the active set (mask) of each iteration so far
  bool periodic = false;
  for (int iter = 0; iter < kIterations; ++iter) {
    std::array<int, kMaxActiveSetPoints> idx;  // the active points, idx[0..m)
    int m = 0;
    unsigned mask = 0;
    for (int i = 0; i < n; ++i)
      if (active[i]) idx[m++] = i, mask |= 1u << i;
    if (!periodic) {
      seen[iter] = mask;
      for (int j = 0; j < iter; ++j)
        if (seen[j] == mask) {  // iterations iter, iter + p, … all start from this set
          const int p = iter - j;
          iter += (kIterations - 1 - iter) / p * p;
          periodic = true;
          break;
        }
    }
    impulse.setZero();
    if (m > 0) {
      Vec3 y = Vec3::Zero();  // D_aᵀ (target − vn) over the active points
      for (int a = 0; a < m; ++a) add_row(y, gap[idx[a]], D, idx[a]);
      const Vec3 z = cache.factor(mask, idx, m) * y;
      for (int a = 0; a < m; ++a) impulse(idx[a]) = row_dot(D, idx[a], z);
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
    Vec3 load = Vec3::Zero();  // Dᵀ j
    for (int i = 0; i < n; ++i) add_row(load, impulse(i), D, i);
    const Vec3 response = cache.system().S * load;  // K j = D S Dᵀ j
    worst_value = -1e-12;
    for (int i = 0; i < n; ++i) {
      if (active[i]) continue;
      const double after = vn(i) + row_dot(D, i, response);
      if (after - target(i) < worst_value) worst = i, worst_value = after - target(i);
    }
    if (worst < 0) break;
    active[worst] = true;
  }
  return impulse;
}

}  // namespace tumble
