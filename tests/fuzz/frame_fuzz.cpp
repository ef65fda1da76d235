// libFuzzer target: arbitrary bytes into the WebSocket frame decoder (the one the tests and
// tools use) and the viewer-side state that applies frames. It must refuse or decode without
// reading out of bounds; whatever it accepts must be version 2, carry at most N records in
// ascending index order below N, and re-encode through FrameDecoder without a trap.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "frame.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const auto frame = tumble::server::decode_frame(bytes);
  if (!frame) return 0;
  if (frame->version != tumble::server::kFrameVersion) __builtin_trap();
  if (frame->bodies.size() > frame->body_count) __builtin_trap();
  for (std::size_t k = 0; k < frame->bodies.size(); ++k) {
    if (frame->bodies[k].index >= frame->body_count) __builtin_trap();
    if (k > 0 && frame->bodies[k].index <= frame->bodies[k - 1].index) __builtin_trap();
  }
  tumble::server::FrameDecoder decoder;
  if (decoder.apply(*frame) != frame->keyframe()) __builtin_trap();
  if (frame->keyframe() && !frame->bodies.empty()) (void)decoder.vertices(frame->bodies.back().index);
  return 0;
}
