#pragma once
/// One flight step of a body under uniform gravity (no torque): the World's integrators.
/// Pure functions; thread-safe.
#include "tumble/body.hpp"
#include "tumble/scene.hpp"

namespace tumble {

/// The state after h seconds of free flight from s with the named integrator.
/// h may be any value in [0, dt]: the impact search evaluates partial steps with it.
BodyState advance(Integrator integrator, const BodyState& s, const BodyConstants& c,
                  const Vec3& gravity, double h);

}  // namespace tumble
