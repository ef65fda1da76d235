#pragma once
/// Narrow phase between two boxes: separating-axis test over the 15 axes and a contact
/// manifold of up to 4 points with feature ids (so impulses persist between steps).
/// Pure functions; thread-safe.
#include <array>
#include <cmath>
#include <cstdint>

#include "tumble/body.hpp"

namespace tumble {

/// Most points a box–box manifold keeps (a face–face patch is reduced to 4).
inline constexpr int kMaxManifoldPoints = 4;

/// One contact point between boxes A and B.
struct ManifoldPoint {
  Vec3 position = Vec3::Zero();  ///< World point midway between the two surfaces, m.
  double separation = 0.0;       ///< Signed gap along the normal, m (< 0: penetration).
  std::uint32_t id = 0;          ///< Feature id: the same touching features give the same id.
};

/// The contact of two boxes: a normal from A to B and up to 4 points.
struct BoxManifold {
  Vec3 normal = Vec3::UnitY();  ///< Unit, world, pointing from A to B.
  int count = 0;                ///< Points in use.
  std::array<ManifoldPoint, kMaxManifoldPoints> points{};
};

/// The manifold of boxes a and b, keeping points whose separation is below `margin` (m, ≥ 0:
/// speculative points closer than the margin are kept so the solver can stop an approach
/// before it penetrates). count == 0 when the boxes are farther apart than the margin, or when
/// the face that would be clipped shows them more than `wanted` (m) apart: every point of the
/// manifold would be at least that far apart, and the caller keeps none of them.
BoxManifold collide_boxes(const BodyState& a, const BodyConstants& ca, const BodyState& b,
                          const BodyConstants& cb, double margin, double wanted = INFINITY);

/// Penetration depth of boxes a and b, m (≤ 0 when they are apart): the least overlap of their
/// projections over the 15 separating axes, which for two boxes is the shortest translation
/// that separates them. Returns as soon as one axis shows the depth is at most `enough`, with
/// that axis's overlap (≤ enough); a result above `enough` is the exact depth (pass −INFINITY
/// to always have it).
double box_depth(const BodyState& a, const BodyConstants& ca, const BodyState& b,
                 const BodyConstants& cb, double enough);

}  // namespace tumble
