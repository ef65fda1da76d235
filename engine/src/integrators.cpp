#include "integrators.hpp"

#include <cstring>

#include "free_rotation.hpp"

namespace tumble {
namespace {

/// dY/dt of the seed, Y = (x, R, P, L): (v, ω* R, F, τ) with F = m g and τ = 0.
struct Derivative {
  Vec3 dx;
  Mat3 dR;
  Vec3 dP;
};

Derivative derivative(const BodyState& s, const BodyConstants& c, const Vec3& gravity) {
  // I⁻¹ = R I_body⁻¹ Rᵀ as in the seed; R need not be orthonormal at the stages.
  const Vec3 w = s.R * c.inv_inertia.cwiseProduct(s.R.transpose() * s.L);
  return {s.P * c.inv_mass, skew(w) * s.R, c.mass * gravity};
}

BodyState add(const BodyState& s, const Derivative& d, double h) {
  BodyState r;
  r.x = s.x + h * d.dx;
  r.R = s.R + h * d.dR;
  r.P = s.P + h * d.dP;
  r.L = s.L;
  return r;
}

BodyState euler(const BodyState& s, const BodyConstants& c, const Vec3& g, double h) {
  BodyState r = add(s, derivative(s, c, g), h);
  orthonormalize(r.R);
  return r;
}

// The seed's second-order step: an Euler half step, then the full step with the derivative
// evaluated at that midpoint (Baraff & Witkin's "midpoint method").
BodyState midpoint(const BodyState& s, const BodyConstants& c, const Vec3& g, double h) {
  const BodyState half = add(s, derivative(s, c, g), 0.5 * h);
  BodyState r = add(s, derivative(half, c, g), h);
  orthonormalize(r.R);
  return r;
}

BodyState rk4(const BodyState& s, const BodyConstants& c, const Vec3& g, double h) {
  const Derivative k1 = derivative(s, c, g);
  const Derivative k2 = derivative(add(s, k1, 0.5 * h), c, g);
  const Derivative k3 = derivative(add(s, k2, 0.5 * h), c, g);
  const Derivative k4 = derivative(add(s, k3, h), c, g);
  BodyState r;
  r.x = s.x + h / 6.0 * (k1.dx + 2.0 * k2.dx + 2.0 * k3.dx + k4.dx);
  r.R = s.R + h / 6.0 * (k1.dR + 2.0 * k2.dR + 2.0 * k3.dR + k4.dR);
  r.P = s.P + h / 6.0 * (k1.dP + 2.0 * k2.dP + 2.0 * k3.dP + k4.dP);
  r.L = s.L;
  orthonormalize(r.R);
  return r;
}

// Semi-implicit Euler as game engines use it: momentum first, then position with the new
// velocity and orientation by the exponential map of the (old-R) angular velocity.
BodyState symplectic_euler(const BodyState& s, const BodyConstants& c, const Vec3& g, double h) {
  BodyState r = s;
  r.P = s.P + h * c.mass * g;
  r.x = s.x + h * c.inv_mass * r.P;
  if (!s.L.isZero()) r.R = rotation_from_vector(h * angular_velocity(s, c)) * s.R;
  return r;
}

/// The torque-free rotation over h of the `exact` and `splitting` integrators.
Mat3 torque_free(Integrator integrator, const BodyState& s, const BodyConstants& c, double h,
                 SpinCache* spin) {
  if (s.L.isZero()) return s.R;  // No spin: nothing to rotate.
  // A cube: ω = L / I is constant, the flow is one rotation (exact for both methods).
  if (c.shape == InertiaShape::isotropic) {
    const Vec3 angle = (h * c.inv_inertia.x()) * s.L;
    if (spin) return cached_turn(angle, *spin) * s.R;
    return rotation_from_vector(angle) * s.R;
  }
  if (integrator == Integrator::exact) return free_rotation_exact(c.inertia, s.R, s.L, h);
  return free_rotation_splitting(c.inertia, s.R, s.L, h);
}

/// The integrators that follow the seed's dY/dt in stages. Kept out of line: inlined into
/// advance, their stack frame and saved registers cost the closed-form step (a cube's whole
/// flight) a quarter of its instructions.
[[gnu::noinline]] BodyState advance_in_stages(Integrator integrator, const BodyState& s,
                                              const BodyConstants& c, const Vec3& gravity,
                                              double h) {
  switch (integrator) {
    case Integrator::euler: return euler(s, c, gravity, h);
    case Integrator::midpoint: return midpoint(s, c, gravity, h);
    case Integrator::rk4: return rk4(s, c, gravity, h);
    default: return symplectic_euler(s, c, gravity, h);  // exact, splitting: never here
  }
}

}  // namespace

// Holding the angle bit for bit matters: ±0 differ, and the turn's zero entries keep their
// signs, so a copied World without the cache agrees.
const Mat3& cached_turn(const Vec3& angle, SpinCache& spin) {
  if (!spin.held || std::memcmp(angle.data(), spin.angle.data(), sizeof(double) * 3) != 0) {
    spin.turn = rotation_from_vector(angle);
    spin.angle = angle;
    spin.held = true;
  }
  return spin.turn;
}

namespace {

// Ballistic translation in closed form, x(h) = x + v h + ½ g h² and P(h) = P + m g h. With
// the attitude after h, this is the whole step of a body in flight; the state is built with
// every field written once (no default state built and overwritten).
Vec3 ballistic_x(const BodyState& s, const BodyConstants& c, const Vec3& gravity, double h) {
  return s.x + h * (c.inv_mass * s.P) + (0.5 * h * h) * gravity;
}
Vec3 ballistic_P(const BodyState& s, const BodyConstants& c, const Vec3& gravity, double h) {
  return s.P + (h * c.mass) * gravity;
}

}  // namespace

BodyState advance(Integrator integrator, const BodyState& s, const BodyConstants& c,
                  const Vec3& gravity, double h, SpinCache* spin) {
  if (integrator != Integrator::exact && integrator != Integrator::splitting)
    return advance_in_stages(integrator, s, c, gravity, h);
  return {ballistic_x(s, c, gravity, h), torque_free(integrator, s, c, h, spin),
          ballistic_P(s, c, gravity, h), s.L};
}

BodyState advance_turned(const BodyState& s, const BodyConstants& c, const Vec3& gravity,
                         double h, const Mat3& rotated) {
  return {ballistic_x(s, c, gravity, h), rotated, ballistic_P(s, c, gravity, h), s.L};
}

}  // namespace tumble
