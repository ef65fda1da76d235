#pragma once
/// The floor's impulses on one box: the normal impulses of its touching vertices (an active-set
/// solve) alternated with Coulomb friction on the contact patch. Pure functions; thread-safe.
#include "floor_geometry.hpp"
#include "friction_rounds.hpp"

namespace tumble::floor_detail {

/// The patch friction impulse of one exchange and its Coulomb limit μ Σ jₙ, N·s.
struct PatchFriction {
  double impulse = 0.0;
  double limit = 0.0;
  /// How far the exchange's last round moved the friction impulse and the twist (N·s, the
  /// twist over the body's bounding radius): 0 when its rounds settled to round-off.
  double unsettled = 0.0;
};

/// Normal velocity each contact should leave with if it is pushed: −eᵢ v⁻ₙ for an approaching
/// contact (e = 0 below the rest speed, which ends a Zeno series), 0 for a resting one.
Impulses normal_targets(const Kinematics& k, const ContactSet& set, double e,
                        double rest_speed_ms);

/// Applies the impulses that leave each vertex of `set` with its normal target (or faster),
/// none pulling, with Coulomb friction μ on the patch as a whole; `patch`, when not null, gets
/// the friction impulse and its limit. Returns the number of vertices in the exchange.
int resolve(BodyState& s, const BodyConstants& c, const ContactSet& set, const Impulses& target,
            double mu, PatchFriction* patch = nullptr);

}  // namespace tumble::floor_detail
