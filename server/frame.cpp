#include "frame.hpp"

#include <bit>
#include <cstring>

namespace tumble::server {
namespace {

template <typename T>
void put(char*& out, T value) {
  using U = std::conditional_t<sizeof(T) == 2, std::uint16_t,
                               std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>;
  const U bits = std::bit_cast<U>(value);
  for (std::size_t i = 0; i < sizeof(U); ++i)
    *out++ = static_cast<char>(static_cast<unsigned char>(bits >> (8 * i)));
}

template <typename T>
T get(const char*& in) {
  using U = std::conditional_t<sizeof(T) == 2, std::uint16_t,
                               std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>;
  U bits = 0;
  for (std::size_t i = 0; i < sizeof(U); ++i)
    bits |= static_cast<U>(static_cast<unsigned char>(*in++)) << (8 * i);
  return std::bit_cast<T>(bits);
}

std::uint8_t activity_code(Activity a) {
  switch (a) {
    case Activity::awake: return 0;
    case Activity::asleep: return 1;
    case Activity::frozen: return 2;
  }
  return 0;
}

// The pose shown at `alpha` ∈ [0, 1] between the previous step (0) and the current one (1).
BodyState shown_state(const BodyPose& now, const BodyPose* before, double alpha) {
  BodyState state;
  if (!before || alpha >= 1.0 || now.activity != Activity::awake) {
    state.x = now.position;
    state.R = now.rotation;
    return state;
  }
  state.x = before->position + alpha * (now.position - before->position);
  const Quat qa(before->rotation);
  const Quat qb(now.rotation);
  state.R = qa.normalized().slerp(alpha, qb.normalized()).toRotationMatrix();
  return state;
}

}  // namespace

std::string encode_frame(const Snapshot& s, std::uint32_t frame_number, double time) {
  const std::vector<BodyPose>& bodies = *s.bodies;
  const std::size_t n = bodies.size();
  std::string frame(kFrameHeaderBytes + kFrameBytesPerBody * n, '\0');
  char* out = frame.data();
  std::memcpy(out, "TMBL", 4);
  out += 4;
  std::uint16_t flags = s.paused ? kFramePaused : 0;
  if (s.frozen > 0) flags |= kFrameSomeFrozen;
  put(out, kFrameVersion);
  put(out, flags);
  put(out, frame_number);
  put(out, static_cast<std::uint32_t>(n));
  put(out, time);
  put(out, s.energy);

  const bool interpolate = s.previous_bodies && s.previous_bodies->size() == n &&
                           s.time > s.previous_time && time < s.time;
  const double alpha =
      interpolate ? (time - s.previous_time) / (s.time - s.previous_time) : 1.0;
  for (std::size_t b = 0; b < n; ++b) {
    const BodyPose* before = interpolate ? &(*s.previous_bodies)[b] : nullptr;
    const BodyState state = shown_state(bodies[b], before, alpha);
    for (int v = 0; v < 8; ++v) {
      const Vec3 p = world_vertex(state, s.scene->constants[b], v);
      put(out, static_cast<float>(p.x()));
      put(out, static_cast<float>(p.y()));
      put(out, static_cast<float>(p.z()));
    }
  }
  for (const BodyPose& p : bodies) *out++ = static_cast<char>(activity_code(p.activity));
  return frame;
}

std::optional<DecodedFrame> decode_frame(std::string_view bytes) {
  if (bytes.size() < kFrameHeaderBytes || bytes.substr(0, 4) != "TMBL") return std::nullopt;
  const char* in = bytes.data() + 4;
  DecodedFrame f;
  f.version = get<std::uint16_t>(in);
  f.flags = get<std::uint16_t>(in);
  f.frame_number = get<std::uint32_t>(in);
  const std::uint32_t n = get<std::uint32_t>(in);
  f.time = get<double>(in);
  f.energy = get<double>(in);
  if (f.version != kFrameVersion || bytes.size() != kFrameHeaderBytes + kFrameBytesPerBody * n)
    return std::nullopt;
  f.vertices.resize(n);
  for (auto& body : f.vertices)
    for (auto& vertex : body)
      for (float& c : vertex) c = get<float>(in);
  f.activity.resize(n);
  for (auto& a : f.activity) a = static_cast<std::uint8_t>(*in++);
  return f;
}

}  // namespace tumble::server
