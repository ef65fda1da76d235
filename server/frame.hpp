#pragma once
/// The binary WebSocket frame of docs/protocol.md (version 1): encoder and decoder.
/// Pure functions; thread-safe.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "snapshot.hpp"

namespace tumble::server {

/// Frame format version written in every frame.
inline constexpr std::uint16_t kFrameVersion = 1;
/// Bytes before the vertex block.
inline constexpr std::size_t kFrameHeaderBytes = 32;
/// Bytes per body: 8 vertices × 3 float32, then one activity byte.
inline constexpr std::size_t kFrameBytesPerBody = 8 * 3 * 4 + 1;
/// Flag bits.
inline constexpr std::uint16_t kFramePaused = 1u << 0;
inline constexpr std::uint16_t kFrameSomeFrozen = 1u << 1;

/// Encodes `s` as frame number `frame_number` showing sim time `time` (s): positions are
/// interpolated between the snapshot's previous and current step when `time` lies between
/// them (centre of mass linearly, orientation by slerp, so boxes stay rigid), else the
/// current pose is used. Vertices come from tumble::world_vertex.
std::string encode_frame(const Snapshot& s, std::uint32_t frame_number, double time);

/// A decoded frame (for tests and tools).
struct DecodedFrame {
  std::uint16_t version = 0;
  std::uint16_t flags = 0;
  std::uint32_t frame_number = 0;
  double time = 0.0;                                         ///< s.
  double energy = 0.0;                                       ///< J.
  std::vector<std::array<std::array<float, 3>, 8>> vertices; ///< Per body, per vertex, xyz.
  std::vector<std::uint8_t> activity;                        ///< 0 awake, 1 asleep, 2 frozen.
};

/// Decodes a frame; nullopt when the bytes are not a well-formed version-1 frame.
std::optional<DecodedFrame> decode_frame(std::string_view bytes);

}  // namespace tumble::server
