// Exact torque-free rotation and the splitting approximation, against closed forms and against
// the high-accuracy reference integrations in tumble_reference. Measured errors are printed
// (and recorded as test properties) so they can be quoted.
#include "free_rotation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tumble_reference/free_rigid_body.hpp"

namespace tumble {
namespace {

using tumble_reference::Method;

// Solid cuboid with full edge lengths (m) and mass (kg): principal moments (kg·m²).
Vec3 box_inertia(const Vec3& size, double mass) {
  const Vec3 s2 = size.cwiseProduct(size);
  return mass / 12.0 * Vec3(s2[1] + s2[2], s2[0] + s2[2], s2[0] + s2[1]);
}

Mat3 some_rotation(double a, double b, double c) {
  return (Eigen::AngleAxisd(a, Vec3::UnitZ()) * Eigen::AngleAxisd(b, Vec3::UnitY()) *
          Eigen::AngleAxisd(c, Vec3::UnitX()))
      .toRotationMatrix();
}

double energy(const Vec3& inertia, const Mat3& R, const Vec3& L) {
  const Vec3 m = R.transpose() * L;
  return 0.5 * m.cwiseProduct(m).cwiseQuotient(inertia).sum();
}

// (M² − 2E I_mid) / (2E I_mid): the signed relative distance from the separatrix.
double separatrix_distance(const Vec3& inertia, const Mat3& R, const Vec3& L) {
  Vec3 sorted = inertia;
  std::sort(sorted.data(), sorted.data() + 3);
  const double two_e_imid = 2.0 * energy(inertia, R, L) * sorted[1];
  return (L.squaredNorm() - two_e_imid) / two_e_imid;
}

void report(const std::string& key, double value) {
  std::printf("  [measured] %-44s %.3e\n", key.c_str(), value);
  ::testing::Test::RecordProperty(key, std::to_string(value));
}

// The project's `tumble` case: 1 × 2 × 3 m box, 1 kg, identity start, ω = (0.01, 2, 0.01).
struct TumbleCase {
  Vec3 inertia = box_inertia({1.0, 2.0, 3.0}, 1.0);
  Mat3 R0 = Mat3::Identity();
  Vec3 L = inertia.cwiseProduct(Vec3(0.01, 2.0, 0.01));
};

TEST(FreeRotationExact, CubeMatchesClosedForm) {
  const Vec3 inertia = box_inertia({1.0, 1.0, 1.0}, 2.0);  // I = 1/3 kg·m² on every axis
  const Mat3 R0 = some_rotation(0.3, -1.1, 2.0);
  const Vec3 L(0.2, -0.5, 0.35);  // ω = 3 L
  double worst = 0.0;
  for (double t : {0.01, 0.5, 1.0, 3.7}) {
    const Vec3 w = L / inertia[0];
    const Mat3 expected = Eigen::AngleAxisd(w.norm() * t, w.normalized()).toRotationMatrix() * R0;
    worst = std::max(worst, rotation_angle_between(expected, free_rotation_exact(inertia, R0, L, t)));
  }
  report("cube_vs_closed_form_rad", worst);
  EXPECT_LT(worst, 1e-14);
}

TEST(FreeRotationExact, ZeroMomentumOrZeroTimeKeepsAttitude) {
  const Vec3 inertia(1.0, 2.0, 3.0);
  const Mat3 R0 = some_rotation(0.1, 0.2, 0.3);
  EXPECT_EQ(free_rotation_exact(inertia, R0, Vec3::Zero(), 5.0), R0);
  EXPECT_EQ(free_rotation_exact(inertia, R0, Vec3(1, 2, 3), 0.0), R0);
}

// Symmetric boxes (prolate 1×1×2 and oblate 2×2×1, and with the distinct axis on x) against
// the long-double reference over 20 s.
TEST(FreeRotationExact, SymmetricBoxMatchesReference) {
  const std::vector<Vec3> sizes{{1.0, 1.0, 2.0}, {2.0, 2.0, 1.0}, {0.5, 1.5, 1.5}};
  const std::vector<double> times{1.0, 5.0, 12.5, 20.0};
  double worst = 0.0;
  for (const Vec3& size : sizes) {
    const Vec3 inertia = box_inertia(size, 1.5);
    const Mat3 R0 = some_rotation(0.7, 0.2, -0.4);
    const Vec3 L(0.4, -0.9, 0.6);
    const auto ref = tumble_reference::free_rigid_body_attitudes(inertia, R0, L, times,
                                                                 Method::kMatrixBulirschStoer);
    for (size_t i = 0; i < times.size(); ++i) {
      const double e = rotation_angle_between(ref[i], free_rotation_exact(inertia, R0, L, times[i]));
      worst = std::max(worst, e);
      EXPECT_LT(e, 1e-11) << "size " << size.transpose() << " t " << times[i];
    }
  }
  report("symmetric_vs_reference_20s_rad", worst);
}

TEST(FreeRotationReference, TwoMethodsAgreeOnTumble) {
  const TumbleCase c;
  std::vector<double> times;
  for (int i = 1; i <= 20; ++i) times.push_back(i);
  const auto a = tumble_reference::free_rigid_body_attitudes(c.inertia, c.R0, c.L, times,
                                                             Method::kQuaternionRkf78);
  const auto b = tumble_reference::free_rigid_body_attitudes(c.inertia, c.R0, c.L, times,
                                                             Method::kMatrixBulirschStoer);
  double worst = 0.0;
  for (size_t i = 0; i < times.size(); ++i) worst = std::max(worst, rotation_angle_between(a[i], b[i]));
  report("tumble_reference_rkf78_vs_bulirsch_stoer_rad", worst);
  EXPECT_LT(worst, 1e-9);
}

TEST(FreeRotationExact, TumbleCaseMatchesReference) {
  const TumbleCase c;
  const double distance = separatrix_distance(c.inertia, c.R0, c.L);
  report("tumble_separatrix_distance", distance);
  EXPECT_GT(distance, 3.0e-6);
  EXPECT_LT(distance, 4.0e-6);

  // Reference at every 1/30 s frame.
  const int steps = 600;
  const double dt = 1.0 / 30.0;
  std::vector<double> times;
  for (int i = 1; i <= steps; ++i) times.push_back(i * dt);
  const auto ref = tumble_reference::free_rigid_body_attitudes(c.inertia, c.R0, c.L, times,
                                                               Method::kMatrixBulirschStoer);

  const Mat3 one_shot = free_rotation_exact(c.inertia, c.R0, c.L, 20.0);
  const double one_shot_error = rotation_angle_between(ref.back(), one_shot);
  report("tumble_one_call_20s_vs_reference_rad", one_shot_error);
  EXPECT_LT(one_shot_error, 1e-8);

  const double e0 = energy(c.inertia, c.R0, c.L);
  Mat3 R = c.R0;
  double worst_composed = 0.0, worst_energy = 0.0, worst_orthonormality = 0.0;
  double worst_direct = 0.0;
  for (int i = 0; i < steps; ++i) {
    R = free_rotation_exact(c.inertia, R, c.L, dt);
    worst_composed = std::max(worst_composed, rotation_angle_between(ref[i], R));
    worst_energy = std::max(worst_energy, std::abs(energy(c.inertia, R, c.L) / e0 - 1.0));
    worst_orthonormality = std::max(worst_orthonormality, orthonormality_error(R));
    if (i % 10 == 9) {  // every 1/3 s, one call from t = 0
      const Mat3 direct = free_rotation_exact(c.inertia, c.R0, c.L, times[i]);
      worst_direct = std::max(worst_direct, rotation_angle_between(ref[i], direct));
    }
  }
  report("tumble_600_steps_worst_vs_reference_rad", worst_composed);
  report("tumble_600_steps_final_vs_reference_rad", rotation_angle_between(ref.back(), R));
  report("tumble_one_call_any_t_worst_vs_reference_rad", worst_direct);
  report("tumble_600_steps_energy_relative", worst_energy);
  report("tumble_600_steps_orthonormality", worst_orthonormality);
  EXPECT_LT(worst_composed, 1e-8);
  EXPECT_LT(worst_direct, 1e-8);
  EXPECT_LT(worst_energy, 1e-13);
  EXPECT_LT(worst_orthonormality, 1e-13);
  // |m| = |L|: the body momentum keeps its length (600 composed rotations, no re-projection).
  const double length_error = std::abs((R.transpose() * c.L).norm() / c.L.norm() - 1.0);
  report("tumble_600_steps_body_momentum_length_relative", length_error);
  EXPECT_LT(length_error, 1e-13);

  // The intermediate axis really flips: m_y changes sign within the 20 s.
  double min_my = 1.0, max_my = -1.0;
  for (const Mat3& r : ref) {
    const double my = (r.transpose() * c.L)[1];
    min_my = std::min(min_my, my);
    max_my = std::max(max_my, my);
  }
  EXPECT_LT(min_my, -1.0);
  EXPECT_GT(max_my, 1.0);
}

struct GeneralCase {
  std::string name;
  Vec3 inertia;
  Mat3 R0;
  Vec3 L;
};

// Both sides of the separatrix, far from it, and every ordering of the moments over the body
// axes; 20 s against the long-double reference.
std::vector<GeneralCase> general_cases() {
  const Vec3 box = box_inertia({1.0, 2.0, 3.0}, 1.0);
  std::vector<GeneralCase> cases;
  // Other side: ω_z a little larger makes M² < 2E I_mid (about −4e-6 from the separatrix).
  cases.push_back({"tumble_other_side", box, Mat3::Identity(),
                   box.cwiseProduct(Vec3(0.01, 2.0, 0.015))});
  cases.push_back({"far_major_axis", box, some_rotation(0.4, 1.0, -0.3),
                   Vec3(0.3, -0.2, 0.9)});
  cases.push_back({"far_minor_axis", box, some_rotation(-1.2, 0.5, 2.1),
                   some_rotation(-1.2, 0.5, 2.1) * box.cwiseProduct(Vec3(0.3, 0.4, 2.5))});
  const std::array<std::array<int, 3>, 6> perms{
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (const auto& p : perms) {
    const Vec3 inertia(0.7 + p[0], 0.7 + 1.3 * p[1], 0.7 + 1.3 * p[2]);
    cases.push_back({"permuted_" + std::to_string(p[0]) + std::to_string(p[1]) +
                         std::to_string(p[2]),
                     inertia, some_rotation(0.3 * p[0], 1.0 - p[1], 0.5 * p[2]),
                     Vec3(-0.8, 1.1, 0.45)});
  }
  return cases;
}

TEST(FreeRotationExact, GeneralCasesMatchReference) {
  const std::vector<double> times{0.25, 3.0, 7.3, 20.0};
  for (const GeneralCase& c : general_cases()) {
    const auto ref = tumble_reference::free_rigid_body_attitudes(c.inertia, c.R0, c.L, times,
                                                                 Method::kMatrixBulirschStoer);
    const double e0 = energy(c.inertia, c.R0, c.L);
    double worst = 0.0, worst_energy = 0.0;
    for (size_t i = 0; i < times.size(); ++i) {
      const Mat3 R = free_rotation_exact(c.inertia, c.R0, c.L, times[i]);
      worst = std::max(worst, rotation_angle_between(ref[i], R));
      worst_energy = std::max(worst_energy, std::abs(energy(c.inertia, R, c.L) / e0 - 1.0));
    }
    std::printf("  %-20s separatrix distance % .3e\n", c.name.c_str(),
                separatrix_distance(c.inertia, c.R0, c.L));
    report(c.name + "_vs_reference_rad", worst);
    report(c.name + "_energy_relative", worst_energy);
    EXPECT_LT(worst, c.name == "tumble_other_side" ? 1e-8 : 1e-11) << c.name;
    EXPECT_LT(worst_energy, 1e-13) << c.name;
  }
}

// A step (|λt| ≤ 1) takes the addition-theorem path, a longer call the half-period reduction:
// single calls from 1/240 s to 4 s cross from one to the other for every case, and composed
// steps of 1/240, 1/30 and 1/15 s over 2 s run the step path only; all against the reference.
TEST(FreeRotationExact, StepsAndLongCallsMatchReference) {
  // Reference times: every 1/240 s up to 2 s (index i − 1 for i/240 s), then 3 and 4 s.
  std::vector<double> times;
  for (int i = 1; i <= 480; ++i) times.push_back(i / 240.0);
  times.push_back(3.0);
  times.push_back(4.0);
  const std::vector<int> single{1, 4, 12, 24, 48, 84, 120, 168, 216, 288, 384, 480, 481, 482};
  const double bound = 1e-12;
  for (const GeneralCase& c : general_cases()) {
    const auto ref = tumble_reference::free_rigid_body_attitudes(c.inertia, c.R0, c.L, times,
                                                                 Method::kMatrixBulirschStoer);
    double worst_single = 0.0;
    for (int i : single) {
      const double t = times[static_cast<size_t>(i - 1)];
      const double e = rotation_angle_between(ref[static_cast<size_t>(i - 1)],
                                               free_rotation_exact(c.inertia, c.R0, c.L, t));
      worst_single = std::max(worst_single, e);
      EXPECT_LT(e, bound) << c.name << " t " << t;
    }
    double worst_composed = 0.0;
    for (int stride : {1, 8, 16}) {  // dt = 1/240, 1/30, 1/15 s
      Mat3 R = c.R0;
      for (int i = stride; i <= 480; i += stride) {
        R = free_rotation_exact(c.inertia, R, c.L, stride / 240.0);
        worst_composed =
            std::max(worst_composed, rotation_angle_between(ref[static_cast<size_t>(i - 1)], R));
      }
    }
    report(c.name + "_single_calls_to_4s_rad", worst_single);
    report(c.name + "_composed_steps_2s_rad", worst_composed);
    EXPECT_LT(worst_composed, bound) << c.name;
  }
}

// The flow is a group: a step back undoes a step forward, and two half steps make one step.
TEST(FreeRotationExact, StepBackAndHalfStepsCompose) {
  double worst_back = 0.0, worst_halves = 0.0;
  for (const GeneralCase& c : general_cases()) {
    for (double t : {1.0 / 240, 1.0 / 30, 0.3}) {
      const Mat3 forward = free_rotation_exact(c.inertia, c.R0, c.L, t);
      const Mat3 back = free_rotation_exact(c.inertia, forward, c.L, -t);
      const Mat3 half = free_rotation_exact(c.inertia, c.R0, c.L, 0.5 * t);
      const Mat3 halves = free_rotation_exact(c.inertia, half, c.L, 0.5 * t);
      worst_back = std::max(worst_back, rotation_angle_between(c.R0, back));
      worst_halves = std::max(worst_halves, rotation_angle_between(forward, halves));
    }
  }
  report("step_back_worst_rad", worst_back);
  report("two_half_steps_worst_rad", worst_halves);
  EXPECT_LT(worst_back, 1e-14);
  EXPECT_LT(worst_halves, 1e-14);
}

// Exactly on the separatrix (k = 1, the sech/tanh limit): inertia (1, 4, 16) and m = (1, ·, 2)
// make M² − 2E I_mid vanish in floating point. The motion is unstable there (round-off grows
// like e^{λt}), so the comparison is over a few seconds only.
TEST(FreeRotationExact, ExactlyOnSeparatrix) {
  const Vec3 inertia(1.0, 4.0, 16.0);
  for (double sign : {1.0, -1.0}) {
    const Vec3 L(sign * 1.0, 0.7, -2.0);  // R0 = I, so m = L
    const std::vector<double> times{0.5, 2.0, 4.0};
    const auto ref = tumble_reference::free_rigid_body_attitudes(
        inertia, Mat3::Identity(), L, times, Method::kMatrixBulirschStoer);
    double worst = 0.0;
    for (size_t i = 0; i < times.size(); ++i) {
      worst = std::max(worst, rotation_angle_between(
                                  ref[i], free_rotation_exact(inertia, Mat3::Identity(), L, times[i])));
    }
    report(sign > 0 ? "on_separatrix_vs_reference_rad" : "on_separatrix_m1_negative_rad", worst);
    EXPECT_LT(worst, 1e-10);
  }
}

// Steady spins about each principal axis are plain rotations about that axis. Axis 0 is the
// middle moment: R0ᵀ(R0 m) leaves ~1e-17 in the other components, so this runs the general
// path a hair from the unstable equilibrium, where k' ~ 1e-17 and the elliptic integrals grow
// like log(1/k') ≈ 40; their round-off allows a few 1e-14 rad, hence 5e-14.
TEST(FreeRotationExact, SteadySpinAboutPrincipalAxes) {
  const Vec3 inertia(2.0, 1.0, 3.0);
  const Mat3 R0 = some_rotation(0.5, -0.3, 1.2);
  for (int axis = 0; axis < 3; ++axis) {
    const Vec3 m = -1.7 * Vec3::Unit(axis);
    const double t = 2.3;
    const Mat3 expected = R0 * axis_rotation(axis, t * m[axis] / inertia[axis]);
    const Mat3 got = free_rotation_exact(inertia, R0, R0 * m, t);
    const double error = rotation_angle_between(expected, got);
    report("steady_spin_axis_" + std::to_string(axis) + "_rad", error);
    EXPECT_LT(error, 5e-14) << "axis " << axis;
  }
}

// Splitting: second order, so halving h divides the error by ~4; |m| and orthonormality to
// round-off whatever h.
double splitting_error(const Vec3& inertia, const Mat3& R0, const Vec3& L, double T, int n) {
  Mat3 R = R0;
  for (int i = 0; i < n; ++i) R = free_rotation_splitting(inertia, R, L, T / n);
  return rotation_angle_between(free_rotation_exact(inertia, R0, L, T), R);
}

TEST(FreeRotationSplitting, IsSecondOrder) {
  for (const GeneralCase& c : general_cases()) {
    if (c.name.rfind("far", 0) != 0) continue;
    const double e1 = splitting_error(c.inertia, c.R0, c.L, 2.0, 200);
    const double e2 = splitting_error(c.inertia, c.R0, c.L, 2.0, 400);
    const double e3 = splitting_error(c.inertia, c.R0, c.L, 2.0, 800);
    report(c.name + "_splitting_h0.01_rad", e1);
    report(c.name + "_splitting_ratio_h/h2", e1 / e2);
    report(c.name + "_splitting_ratio_h2/h4", e2 / e3);
    EXPECT_NEAR(e1 / e2, 4.0, 0.3) << c.name;
    EXPECT_NEAR(e2 / e3, 4.0, 0.3) << c.name;
  }
}

TEST(FreeRotationSplitting, TumbleCaseAccuracyAndInvariants) {
  const TumbleCase c;
  Mat3 R = c.R0;
  const double e0 = energy(c.inertia, c.R0, c.L);
  double worst_energy = 0.0;
  for (int i = 0; i < 600; ++i) {
    R = free_rotation_splitting(c.inertia, R, c.L, 1.0 / 30.0);
    worst_energy = std::max(worst_energy, std::abs(energy(c.inertia, R, c.L) / e0 - 1.0));
  }
  const double error = rotation_angle_between(free_rotation_exact(c.inertia, c.R0, c.L, 20.0), R);
  report("tumble_splitting_600_steps_vs_exact_rad", error);
  report("tumble_splitting_energy_relative", worst_energy);
  EXPECT_NEAR((R.transpose() * c.L).norm() / c.L.norm(), 1.0, 1e-14);
  EXPECT_LT(orthonormality_error(R), 1e-13);
  // Energy error of a symplectic splitting stays bounded (O(h²)), it does not drift.
  EXPECT_LT(worst_energy, 1e-3);
  // Second order at h = 1/30 s near the separatrix: a visible but bounded attitude error.
  EXPECT_LT(error, 0.5);
  const double e1 = splitting_error(c.inertia, c.R0, c.L, 2.0, 200);
  const double e2 = splitting_error(c.inertia, c.R0, c.L, 2.0, 400);
  report("tumble_splitting_ratio_h/h2_over_2s", e1 / e2);
  EXPECT_NEAR(e1 / e2, 4.0, 0.4);
}

// free_rotation_exact_many gives each body the bits free_rotation_exact gives it alone, in
// every case its lanes meet: general boxes of every aspect (and cubes, symmetric and
// near-symmetric boxes, which take the closed forms), steady spins about each axis, spins
// from a hair off a steady spin to fast enough that a lane leaves the short form, near and
// exactly on the separatrix, no spin, and odd counts (unused lanes). A lane that differs in
// one bit fails the memcmp.
TEST(FreeRotationExact, ManyInLanesGiveTheBitsOfOneAtATime) {
  std::uint64_t seed = 12345;
  auto uniform = [&seed](double lo, double hi) {  // a fixed 64-bit LCG, the same everywhere
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * static_cast<double>(seed >> 11) * 0x1.0p-53;
  };
  struct Body {
    Vec3 inertia, L;
    Mat3 R;
  };
  std::vector<Body> bodies;
  for (int i = 0; i < 4000; ++i) {
    Body b;
    const Vec3 size(uniform(0.2, 0.6), uniform(0.2, 0.6), uniform(0.2, 0.6));
    b.inertia = box_inertia(size, uniform(1.0, 10.0));
    if (i % 50 == 1) b.inertia = box_inertia({0.4, 0.4, 0.4}, 2.0);      // cube
    if (i % 50 == 2) b.inertia = box_inertia({0.3, 0.3, 0.5}, 2.0);      // symmetric
    if (i % 50 == 3) b.inertia[1] = b.inertia[0] * (1.0 + 1e-15);        // near-symmetric
    b.R = some_rotation(uniform(-3.0, 3.0), uniform(-1.5, 1.5), uniform(-3.0, 3.0));
    // ω up to 3 rad/s, and every 7th body up to 300 rad/s (long increments, ψ past the series).
    const double w = i % 7 == 0 ? 300.0 : 3.0;
    Vec3 omega(uniform(-w, w), uniform(-w, w), uniform(-w, w));
    if (i % 50 == 4) omega = Vec3(1e-9, 2.0, -1e-9);                    // near a steady spin
    if (i % 50 == 5) omega = Vec3::Zero();                              // no spin
    if (i % 50 >= 6 && i % 50 <= 8) {                                   // steady spins
      b.R = Mat3::Identity();
      omega = Vec3::Unit(i % 50 - 6) * uniform(-3.0, 3.0);
    }
    b.L = b.R * b.inertia.cwiseProduct(omega);
    bodies.push_back(b);
  }
  // Exactly on the separatrix, both signs of m1 (R = I, so m = L).
  bodies.push_back({Vec3(1.0, 4.0, 16.0), Vec3(1.0, 0.7, -2.0), Mat3::Identity()});
  bodies.push_back({Vec3(1.0, 4.0, 16.0), Vec3(-1.0, 0.7, -2.0), Mat3::Identity()});
  for (double t : {1.0 / 240.0, 1.0 / 60.0, 1.0 / 30.0, 0.7}) {
    for (std::size_t count : {bodies.size(), std::size_t{3}, std::size_t{2}, std::size_t{1}}) {
      std::vector<Mat3> got(count);
      std::vector<FreeFlow> flows;
      for (std::size_t i = 0; i < count; ++i)
        flows.push_back({&bodies[i].inertia, &bodies[i].R, &bodies[i].L, &got[i]});
      free_rotation_exact_many(flows, t);
      for (std::size_t i = 0; i < count; ++i) {
        const Body& b = bodies[i];
        const Mat3 alone = free_rotation_exact(b.inertia, b.R, b.L, t);
        ASSERT_EQ(std::memcmp(alone.data(), got[i].data(), sizeof(Mat3)), 0)
            << "body " << i << " of " << count << ", t = " << t;
      }
    }
  }
}

}  // namespace
}  // namespace tumble
