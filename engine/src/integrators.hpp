#pragma once
/// One flight step of a body under uniform gravity (no torque): the World's integrators.
/// Pure functions; thread-safe.
#include <cstdint>

#include "tumble/body.hpp"
#include "tumble/scene.hpp"

namespace tumble {

/// The state after h seconds of free flight from s with the named integrator.
/// h may be any value in [0, dt]: the impact search evaluates partial steps with it.
/// Euler, midpoint and RK4 re-orthonormalise R; the others compose exact rotations, whose
/// round-off the World removes every kGramSchmidtInterval steps.
/// Steps between Gram–Schmidt passes over R for the geometric integrators: a product of
/// exact rotations drifts from SO(3) like a random walk of 1e-16 per step, so one pass every
/// 64 steps keeps ‖RᵀR − I‖ near 1e-15 at a sixty-fourth of the cost.
inline constexpr std::uint64_t kGramSchmidtInterval = 64;

/// The turn of a cube (an isotropic body) in one step of torque-free flight, kept between
/// steps: ω = L / I is constant in flight, so the turn exp(h ω×) is the same matrix step after
/// step, and it is recomputed only when h ω changes. The same bits as computing it afresh.
/// One per body; not thread-safe (each body's cache is used by one thread at a time).
struct SpinCache {
  Vec3 angle = Vec3::Zero();     ///< h ω it holds, rad.
  Mat3 turn = Mat3::Identity();  ///< rotation_from_vector(angle).
  bool held = false;             ///< Whether it holds a turn yet.
};

/// rotation_from_vector(angle), from `spin` when it holds that angle bit for bit (then the
/// same bits without the work); otherwise computed and kept in `spin`. Not thread-safe on
/// one spin.
const Mat3& cached_turn(const Vec3& angle, SpinCache& spin);

/// `advance` with a cube's turn taken from `spin` when it holds this step's (spin may be null).
BodyState advance(Integrator integrator, const BodyState& s, const BodyConstants& c,
                  const Vec3& gravity, double h, SpinCache* spin = nullptr);

/// `advance` of `exact` or `splitting` given the attitude after h, `rotated`: the torque-free
/// flow from this s over this h, computed beforehand (free_rotation_exact_many, several bodies
/// at once). The same bits as `advance` when `rotated` has them.
BodyState advance_turned(const BodyState& s, const BodyConstants& c, const Vec3& gravity,
                         double h, const Mat3& rotated);

}  // namespace tumble
