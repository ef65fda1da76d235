#pragma once
/// Torque-free rotation of a rigid body: exact flows and the splitting approximation.
/// Pure functions; thread-safe.
#include <span>

#include "tumble/math.hpp"

namespace tumble {

/// Exact torque-free attitude after t seconds: R(t) for a body with principal moments
/// `inertia` (kg·m², body axes), starting at orientation R (body → world) with constant world
/// angular momentum L (kg·m²/s). Cube: one rotation; two equal moments: regular precession;
/// general: Jacobi elliptic functions and elliptic integrals (Celledoni, Fassò, Säfström &
/// Zanna, SIAM J. Sci. Comput. 30(4), 2008).
Mat3 free_rotation_exact(const Vec3& inertia, const Mat3& R, const Vec3& L, double t);

/// One body's free_rotation_exact: its inputs, and where R(t) goes (not aliasing them).
struct FreeFlow {
  const Vec3* inertia;
  const Mat3* R;
  const Vec3* L;
  Mat3* out;
};

/// free_rotation_exact for every flow over the same t (s), with the same bits as one at a
/// time; the general boxes' elliptic phases run four at a time in SIMD lanes
/// (free_rotation_lanes.cpp).
void free_rotation_exact_many(std::span<const FreeFlow> flows, double t);

/// Second-order symmetric splitting of the free rotation (McLachlan 1993; Dullweber,
/// Leimkuhler & McLachlan 1997): H = T1 + T2 + T3, each an exact rotation about one body axis.
/// L is conserved exactly, R stays orthonormal to round-off.
Mat3 free_rotation_splitting(const Vec3& inertia, const Mat3& R, const Vec3& L, double t);

}  // namespace tumble
