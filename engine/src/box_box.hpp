#pragma once
/// Narrow phase between two boxes: separating-axis test over the 15 axes and a contact
/// manifold of up to 4 points with feature ids (so impulses persist between steps).
/// Pure functions; thread-safe.
#include <array>
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
  Vec3 local_a = Vec3::Zero();   ///< The point on A's surface, A's frame, m (for recycling).
  Vec3 local_b = Vec3::Zero();   ///< The point on B's surface, B's frame, m.
};

/// The contact of two boxes: a normal from A to B and up to 4 points.
struct BoxManifold {
  Vec3 normal = Vec3::UnitY();  ///< Unit, world, pointing from A to B.
  int count = 0;                ///< Points in use.
  std::array<ManifoldPoint, kMaxManifoldPoints> points{};
  Vec3 local_normal = Vec3::UnitY();  ///< The normal in A's frame.
  Mat3 relative_R = Mat3::Identity(); ///< Aᵀ B when the manifold was found.
  Vec3 relative_x = Vec3::Zero();     ///< B's centre in A's frame then, m.
};

/// Fills the manifold's local anchors, local normal and relative pose from its world points
/// for boxes a and b as they are now (the pose it was found at).
void anchor_manifold(BoxManifold& m, const BodyState& a, const BodyState& b);

/// True when b's pose relative to a is within `distance` (m, each coordinate of B's centre in
/// A's frame) and `angle` (rad, each entry of AᵀB) of the pose m was found at.
bool pose_close(const BoxManifold& m, const BodyState& a, const BodyState& b, double distance,
                double angle);

/// m moved with its bodies to their poses now: each point's anchors on A and on B placed in
/// the world, the point midway, its separation along A's turned normal (ids unchanged).
void move_manifold(BoxManifold& m, const BodyState& a, const BodyState& b);

/// The manifold of boxes a and b, keeping points whose separation is below `margin` (m, ≥ 0:
/// speculative points closer than the margin are kept so the solver can stop an approach
/// before it penetrates). count == 0 when the boxes are farther apart than the margin.
BoxManifold collide_boxes(const BodyState& a, const BodyConstants& ca, const BodyState& b,
                          const BodyConstants& cb, double margin);

}  // namespace tumble
