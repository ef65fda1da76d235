#pragma once
/// The rounds of one floor impulse exchange (floor_impulse.cpp's `resolve`): the map G from
/// one round's friction to the next, Anderson mixing of its inputs, and Newton's method on
/// its fixed point for an exchange the rounds leave far off. Pure; thread-safe.
#include <array>

#include <Eigen/Core>

#include "active_set.hpp"
#include "floor_geometry.hpp"

namespace tumble::floor_detail {

/// One normal impulse or target per touching vertex (N·s, m/s).
using Impulses = std::array<double, kMaxPoints>;

/// Applies the active-set normal impulses (active_set.hpp) to s and k; returns them per
/// vertex.
Impulses solve_normal(BodyState& s, Kinematics& k, const ContactSet& set, ActiveSetCache& system,
                      const Impulses& target);

/// What one round applies: the patch friction impulse F (N·s, along x and z) at `at` (m, from
/// the centre of mass) and the twist about the normal (N·m·s).
struct RoundInput {
  Eigen::Vector2d friction = Eigen::Vector2d::Zero();
  double twist = 0.0;
  Vec3 at = Vec3::Zero();
};

/// What a round finds: the next round's input G(x) and the Coulomb limit μ Σ jₙ of the loads
/// it was found at (N·s; 0: no load, the body leaves the floor, and `next` is not set).
struct RoundOutput {
  RoundInput next;
  double limit = 0.0;
};

/// The unknowns of the rounds as one vector (F_x, F_z, τ / r, at), N·s and m: the twist over
/// the body's bounding radius r (`lever`) shares the friction's units.
using RoundVector = Eigen::Matrix<double, 6, 1>;
/// x as a vector; the inverse of round_input.
RoundVector round_vector(const RoundInput& x, double lever);
/// The input of vector v; the inverse of round_vector.
RoundInput round_input(const RoundVector& v, double lever);

/// How far the output of a round moved from its input: |ΔF| + |Δτ| / lever, N·s.
double round_residual(const RoundInput& in, const RoundInput& out, double lever);

/// The map G of one exchange: a round applies its input to the state before the exchange,
/// solves the normal impulses, and takes as the next friction the impulse that cancels the
/// sliding at the loads' centroid through its 2×2 tangential mass, clamped to the cone
/// μ Σ jₙ, and as the next twist the one that stops the spin about the normal, clamped to
/// μ Σ jₙ times the loads' mean lever. Holds references to its arguments.
class FrictionRounds {
 public:
  FrictionRounds(const BodyState& s0, const Kinematics& k0, const ContactSet& set,
                 ActiveSetCache& system, const Impulses& target, double mu)
      : s0_(s0), k0_(k0), set_(set), system_(system), target_(target), mu_(mu) {}

  /// Applies `in` to the state before the exchange into s and k, then the normal impulses,
  /// which it returns.
  Impulses apply(const RoundInput& in, BodyState& s, Kinematics& k) const;
  /// G(in), from the normal impulses and kinematics that apply(in) left.
  RoundOutput read(const RoundInput& in, const Impulses& normal, const Kinematics& k) const;
  /// G(in) from the start: apply, then read.
  RoundOutput operator()(const RoundInput& in) const;

 private:
  const BodyState& s0_;
  const Kinematics& k0_;
  const ContactSet& set_;
  ActiveSetCache& system_;
  const Impulses& target_;
  double mu_;
};

/// Anderson mixing of depth 2 over the rounds' vectors (friction_rounds.cpp says why).
class RoundMixer {
 public:
  /// The next round's input from this round's input x and output g = G(x).
  RoundVector next(const RoundVector& x, const RoundVector& g);

 private:
  int count_ = 0;  // rounds in the history since the last restart
  // The last round's residual and output, and their changes over the last two rounds.
  RoundVector f_ = RoundVector::Zero(), g_ = RoundVector::Zero();
  RoundVector df0_ = RoundVector::Zero(), dg0_ = RoundVector::Zero();
  RoundVector df1_ = RoundVector::Zero(), dg1_ = RoundVector::Zero();
};

/// The round of an exchange closest to its fixed point so far: its residual (round_residual,
/// N·s), its output and the limit it was found at.
struct ClosestRound {
  double residual = INFINITY;
  RoundInput output;
  double limit = 0.0;
};

/// Newton's method on G(x) = x from `best`'s output, a few steps; `best` takes any round
/// that comes closer to its fixed point.
void polish(const FrictionRounds& rounds, double lever, ClosestRound& best);

}  // namespace tumble::floor_detail
