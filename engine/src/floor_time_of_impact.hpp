#pragma once
/// When a box in flight first meets the floor within a step: a guess from each vertex's
/// cubic Hermite interpolant, checked and closed by evaluations of the trajectory, TOMS 748
/// where the guess fails. Pure functions; thread-safe.
#include "floor_geometry.hpp"
#include "tumble/scene.hpp"

namespace tumble::floor_detail {

/// Earliest time in [0, h] at which a vertex of `mask` reaches the floor (it is above at 0
/// and some vertex of the mask is below at h, in the state `end`). Returns the non-penetrating
/// end of the final bracket, so a body is never left inside the floor, and sets `at` to the
/// body's state then.
///
/// Both searches end on a time they evaluated with the body above the floor (the lower end of
/// the bracket), so that evaluation's state is kept rather than computed again: the latest
/// time evaluated above the floor is that end. One trajectory evaluation saved per impact,
/// the same bits.
double time_of_impact(const BodyState& s, const BodyState& end, const BodyConstants& c,
                      const WorldDef& w, double floor_y, double h, unsigned mask,
                      double height_at_h, int& evaluations, BodyState& at);

}  // namespace tumble::floor_detail
