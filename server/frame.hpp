#pragma once
/// The binary WebSocket frame of docs/protocol.md (version 2): keyframes and deltas of
/// quantised box poses. Encoder, stateless decoder, and the viewer-side state that applies
/// deltas (for tests and tools). Pure functions and value types; thread-safe.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "frame_state.hpp"

namespace tumble::server {

/// Frame format version written in every frame.
inline constexpr std::uint16_t kFrameVersion = 2;
/// Bytes of the fixed header.
inline constexpr std::size_t kFrameHeaderBytes = 40;
/// Header flag bits.
inline constexpr std::uint16_t kFramePaused = 1u << 0;
inline constexpr std::uint16_t kFrameSomeFrozen = 1u << 1;
inline constexpr std::uint16_t kFrameKeyframe = 1u << 2;
inline constexpr std::uint16_t kFrameBitmap = 1u << 3;
/// Body record format byte: bits 0–1 activity, this bit: absolute centre, then wide axes,
/// bits 4–7: axis exponent − kMinAxisExponent.
inline constexpr std::uint8_t kRecordAbsolute = 1u << 2;
inline constexpr std::uint8_t kRecordWide = 1u << 3;

/// Encodes frame `f` for a viewer that holds frame `base` (null: it holds nothing of this
/// scene). A keyframe (every body, absolute centres) when `base` is null or of another
/// generation; else a delta with only the bodies changed after `base`, centres relative to
/// `base`'s where they fit int16. `base` must be older than `f`.
std::string encode_frame(const FrameState& f, const FrameState* base);

/// One body record of a decoded frame.
struct DecodedBody {
  std::uint32_t index = 0;   ///< Body index in the scene.
  QuantBody body;            ///< Axes, exponent, width, activity; centre as sent.
  bool absolute = true;      ///< Centre is absolute (else relative to the base frame's).
};

/// A decoded frame, as sent (deltas not applied).
struct DecodedFrame {
  std::uint16_t version = 0;
  std::uint16_t flags = 0;
  std::uint32_t frame_number = 0;
  std::uint32_t base_number = 0;    ///< The frame this one is relative to (itself if key).
  std::uint32_t body_count = 0;     ///< N, bodies in the scene.
  double time = 0.0;                ///< s.
  double energy = 0.0;              ///< J.
  std::vector<DecodedBody> bodies;  ///< The records, ascending index.
  /// True for a keyframe.
  bool keyframe() const { return (flags & kFrameKeyframe) != 0; }
};

/// Decodes a frame; nullopt when the bytes are not a well-formed version-2 frame (wrong
/// magic or version, lengths that disagree, indices out of range or not ascending).
std::optional<DecodedFrame> decode_frame(std::string_view bytes);

/// What a viewer holds: the last frame applied and every body's quantised pose.
class FrameDecoder {
 public:
  /// Applies a frame; false (state unchanged) when it is a delta against a frame other than
  /// the last one applied, or of another body count.
  bool apply(const DecodedFrame& frame);
  /// Bodies held.
  const std::vector<QuantBody>& bodies() const { return bodies_; }
  /// World vertices of body `b`, m.
  std::array<Vec3, 8> vertices(std::size_t b) const;
  /// The last frame applied (number, time, flags); nullopt before the first keyframe.
  const std::optional<DecodedFrame>& last() const { return last_; }

 private:
  std::vector<QuantBody> bodies_;
  std::optional<DecodedFrame> last_;
};

}  // namespace tumble::server
