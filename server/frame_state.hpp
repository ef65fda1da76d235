#pragma once
/// The quantised state of every body at one frame (docs/protocol.md, version 2): what the
/// frames of that instant are encoded from, and what a later frame's delta is taken against.
/// Built once per frame by the broadcaster; immutable afterwards, so thread-safe to share.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "snapshot.hpp"

namespace tumble::server {

/// Unit of a body's centre on the wire: 2⁻¹⁶ m ≈ 15.3 µm (int32: ±32,768 m).
inline constexpr double kCentreUnit = 1.0 / 65536.0;
/// Smallest and largest exponent e of a body's axis unit 2⁻ᵉ m (4 bits on the wire).
inline constexpr int kMinAxisExponent = 8;
inline constexpr int kMaxAxisExponent = 23;
/// Narrow (int16) axes are used only when their unit is at most 2⁻¹⁵ m (the error bound).
inline constexpr int kMinNarrowExponent = 15;

/// One body quantised: its centre and three rotated half-edge vectors a, b, d, so that
/// vertex i = centre ± a ± b ± d exactly (bit 0 of i: +a, bit 1: +b, bit 2: +d).
struct QuantBody {
  std::array<std::int32_t, 3> centre{};  ///< Units of kCentreUnit, world frame.
  std::array<std::int32_t, 9> axes{};    ///< a, b, d (x, y, z each) in units of 2⁻ᵉ m.
  std::uint8_t exponent = kMinNarrowExponent;  ///< e; fixed per body by its size.
  bool wide = false;                     ///< Axes need int32 (boxes over ~2 m).
  std::uint8_t activity = 0;             ///< 0 awake, 1 asleep, 2 frozen.
  /// Same pose and activity (what "changed" means for deltas).
  bool operator==(const QuantBody&) const = default;
};

/// The axis encoding of a box with half edge lengths `half_extents` (m): the largest exponent
/// whose int16 range holds every component, or int32 when int16 would be coarser than 2⁻¹⁵ m.
void choose_axis_encoding(const Vec3& half_extents, QuantBody& body);

/// Quantises a pose (centre of mass `x`, body→world rotation `R`) into `body`, keeping its
/// exponent and width. Returns false, leaving `body`'s pose untouched, when the pose is not
/// finite (so a body is never sent as NaN).
bool quantise_pose(const Vec3& x, const Mat3& R, const Vec3& half_extents, QuantBody& body);

/// The world position of vertex `i` (0…7) of a quantised body, m (exact sums of the units).
Vec3 quantised_vertex(const QuantBody& body, int i);

/// All bodies of one frame plus when each last changed (for "changed since frame m").
struct FrameState {
  std::uint32_t number = 0;        ///< Frame number (broadcaster's count since start).
  std::uint64_t generation = 0;    ///< Scene generation.
  std::uint16_t flags = 0;         ///< Paused / some frozen bits of the frame header.
  double time = 0.0;               ///< Sim time shown, s.
  double energy = 0.0;             ///< J.
  std::vector<QuantBody> bodies;   ///< Per body.
  /// Per body: the number of the frame at which its QuantBody last changed (within this
  /// generation); the first frame of a generation counts as a change of every body.
  std::vector<std::uint32_t> changed_at;
  std::uint32_t last_change = 0;   ///< Largest changed_at (frame of the newest change).
};

/// The state of frame `number` from snapshot `s` shown at sim time `time` (interpolated as in
/// encode_frame's rules), against the previous frame's state `previous` (null, or another
/// generation: every body counts as changed).
std::shared_ptr<const FrameState> make_frame_state(const Snapshot& s, std::uint32_t number,
                                                   double time,
                                                   const FrameState* previous);

}  // namespace tumble::server
