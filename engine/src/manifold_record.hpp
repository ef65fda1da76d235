#pragma once
/// Box–box manifolds kept between steps in their bodies' frames and reused while a pair
/// barely moves (Box2D v3.2's manifold recycling; the persistent manifolds of Bullet and PhysX
/// likewise keep points in the bodies' frames). Pure functions; thread-safe.
#include <array>
#include <cstdint>

#include "box_box.hpp"
#include "tumble/body.hpp"

namespace tumble {

/// How far a pair may move from the pose its record was found at and still reuse it: b's
/// centre in a's frame, and each point of either box (the relative turn times the two
/// bounding radii), m. A pair is recorded only in a step where it moves less than this.
//
// Why 1 mm: a recycled point is a pair of material points, one on each box, so its
// separation at the new pose is exact for those two points; what may go stale is the choice
// of points. Within 1 mm of the recorded pose the true patch's corners are within 1 mm of
// the recorded ones (on unit boxes, a thousandth of the face), and a feature that was
// farther than the speculative margin (2 cm) when recorded is still over 1.9 cm away, out of
// reach of a pair moving under 1 mm a step. Measured (callgrind, `pyramid`'s 30 timed steps,
// and the stacks' probe of docs/engine-log.md): 1e-5 m recycled 30 % of `pyramid`'s manifolds
// for 1.2 % fewer instructions in `World::step`, 1e-4 m 6.3 %, 1e-3 m 7.5 %, with the same
// deepest overlaps, top-box travel and sleep times to two digits.
inline constexpr double kRecycleDistance = 1e-3;

/// A box–box manifold in the frames of its two bodies: each point's two surface points as
/// material points of a and of b, the normal in a's frame, and the pose it was found at.
struct ManifoldRecord {
  Vec3 offset = Vec3::Zero();  ///< b's centre in a's frame, m.
  Mat3 turn = Mat3::Zero();    ///< R_aᵀ R_b.
  Vec3 normal = Vec3::UnitY(); ///< The manifold's normal in a's frame.
  int count = 0;               ///< Points in use.
  std::array<Vec3, kMaxManifoldPoints> on_a{};  ///< Each point's surface point on a, a's frame, m.
  std::array<Vec3, kMaxManifoldPoints> on_b{};  ///< Each point's surface point on b, b's frame, m.
  std::array<std::uint32_t, kMaxManifoldPoints> id{};  ///< Feature ids.
};

/// The record of manifold m, found with the boxes at poses a and b.
ManifoldRecord record_manifold(const BoxManifold& m, const BodyState& a, const BodyState& b);

/// The manifold of `record` moved with the boxes to poses a and b (each point's separation
/// that of its two material points along the normal): true when the pair is still within
/// kRecycleDistance of the record's pose, else false and `out` untouched. ra and rb are the
/// boxes' bounding radii, m.
bool recycle_manifold(const ManifoldRecord& record, const BodyState& a, double ra,
                      const BodyState& b, double rb, BoxManifold& out);

}  // namespace tumble
