// libFuzzer target: arbitrary bytes into the WebSocket frame decoder (the one the tests and
// tools use). It must refuse or decode without reading out of bounds, and whatever it
// accepts must have the documented length 32 + 97 N and one activity byte per body.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "frame.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const auto frame = tumble::server::decode_frame(bytes);
  if (!frame) return 0;
  const std::size_t n = frame->vertices.size();
  if (frame->activity.size() != n) __builtin_trap();
  if (size != tumble::server::kFrameHeaderBytes + tumble::server::kFrameBytesPerBody * n)
    __builtin_trap();
  if (frame->version != tumble::server::kFrameVersion) __builtin_trap();
  return 0;
}
