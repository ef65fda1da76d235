#pragma once
/// A box resting on one corner or one edge of the floor that sticks, turned about it over a
/// step to second order (floor_contact.cpp decides when). Pure functions; thread-safe.
#include "tumble/body.hpp"

namespace tumble {

/// A box on a sticking edge (vertices r0, r1 from the centre, world, m) over h seconds: the
/// Störmer–Verlet step of the pendulum about the edge, given the angular velocities before
/// and after the contact solve (w_start, w_end, rad/s) and the solved state `s`.
void edge_step(BodyState& s, const BodyConstants& c, const Vec3& gravity, double h,
               const Vec3& w_start, const Vec3& w_end, const Vec3& r0, const Vec3& r1);

/// A box on a sticking corner (r0 from the centre, world, m) over h seconds: the heavy top's
/// splitting about the corner, from the momenta before the contact solve (p_start, N·s;
/// L_start, N·m·s) and the solved state `s` (its pose is still the step's start).
void corner_step(BodyState& s, const BodyConstants& c, const Vec3& gravity, double h,
                 const Vec3& p_start, const Vec3& L_start, const Vec3& r0);

}  // namespace tumble
