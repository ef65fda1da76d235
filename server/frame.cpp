#include "frame.hpp"

#include <bit>
#include <cstring>
#include <limits>

namespace tumble::server {
namespace {

template <typename T>
void put(std::string& out, T value) {
  using U = std::conditional_t<sizeof(T) == 1, std::uint8_t,
            std::conditional_t<sizeof(T) == 2, std::uint16_t,
            std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
  const U bits = std::bit_cast<U>(value);
  for (std::size_t i = 0; i < sizeof(U); ++i)
    out.push_back(static_cast<char>(static_cast<unsigned char>(bits >> (8 * i))));
}

// A bounds-checked little-endian reader.
struct Reader {
  std::string_view bytes;
  std::size_t at = 0;
  bool ok = true;
  template <typename T>
  T get() {
    using U = std::conditional_t<sizeof(T) == 1, std::uint8_t,
              std::conditional_t<sizeof(T) == 2, std::uint16_t,
              std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;
    if (!ok || bytes.size() - at < sizeof(U)) {
      ok = false;
      return T{};
    }
    U bits = 0;
    for (std::size_t i = 0; i < sizeof(U); ++i)
      bits |= static_cast<U>(static_cast<unsigned char>(bytes[at++])) << (8 * i);
    return std::bit_cast<T>(bits);
  }
};

bool fits_int16(std::int64_t v) {
  return v >= std::numeric_limits<std::int16_t>::min() &&
         v <= std::numeric_limits<std::int16_t>::max();
}

void put_record(std::string& out, const QuantBody& q, const QuantBody* base) {
  bool absolute = base == nullptr;
  std::array<std::int64_t, 3> delta{};
  for (int k = 0; k < 3 && !absolute; ++k) {
    delta[k] = static_cast<std::int64_t>(q.centre[k]) - base->centre[k];
    absolute = !fits_int16(delta[k]);
  }
  const auto format = static_cast<std::uint8_t>(
      (q.activity & 3u) | (absolute ? kRecordAbsolute : 0u) | (q.wide ? kRecordWide : 0u) |
      ((q.exponent - kMinAxisExponent) << 4));
  put(out, format);
  for (int k = 0; k < 3; ++k) {
    if (absolute) put(out, q.centre[k]);
    else put(out, static_cast<std::int16_t>(delta[k]));
  }
  for (const std::int32_t a : q.axes) {
    if (q.wide) put(out, a);
    else put(out, static_cast<std::int16_t>(a));
  }
}

// Which bodies a delta carries: those whose quantised pose changed after the base frame.
std::vector<std::uint32_t> changed_since(const FrameState& f, std::uint32_t base_number) {
  std::vector<std::uint32_t> changed;
  if (f.last_change <= base_number) return changed;
  for (std::size_t b = 0; b < f.changed_at.size(); ++b)
    if (f.changed_at[b] > base_number) changed.push_back(static_cast<std::uint32_t>(b));
  return changed;
}

void put_selection(std::string& out, const std::vector<std::uint32_t>& changed, std::size_t n,
                   bool bitmap) {
  if (!bitmap) {
    for (const std::uint32_t b : changed) put(out, b);
    return;
  }
  std::string bits((n + 7) / 8, '\0');
  for (const std::uint32_t b : changed) bits[b / 8] = static_cast<char>(bits[b / 8] | (1 << (b % 8)));
  out += bits;
}

}  // namespace

std::string encode_frame(const FrameState& f, const FrameState* base) {
  const std::size_t n = f.bodies.size();
  const bool key = !base || base->generation != f.generation || base->bodies.size() != n;
  std::vector<std::uint32_t> changed;
  if (!key) changed = changed_since(f, base->number);
  const std::size_t m = key ? n : changed.size();
  const bool bitmap = !key && (n + 7) / 8 < 4 * m;
  std::uint16_t flags = f.flags;
  if (key) flags |= kFrameKeyframe;
  if (bitmap) flags |= kFrameBitmap;

  std::string out;
  out.reserve(kFrameHeaderBytes + (bitmap ? (n + 7) / 8 : 4 * m) + m * (1 + 12 + 36));
  out.append("TMBL", 4);
  put(out, kFrameVersion);
  put(out, flags);
  put(out, f.number);
  put(out, key ? f.number : base->number);
  put(out, static_cast<std::uint32_t>(n));
  put(out, static_cast<std::uint32_t>(m));
  put(out, f.time);
  put(out, f.energy);
  if (key) {
    for (const QuantBody& q : f.bodies) put_record(out, q, nullptr);
    return out;
  }
  put_selection(out, changed, n, bitmap);
  for (const std::uint32_t b : changed) put_record(out, f.bodies[b], &base->bodies[b]);
  return out;
}

namespace {

bool read_selection(Reader& in, DecodedFrame& f, std::uint32_t m) {
  const std::uint32_t n = f.body_count;
  if (f.keyframe()) {
    if (m != n) return false;
    for (std::uint32_t b = 0; b < n; ++b) f.bodies[b].index = b;
    return true;
  }
  if (f.flags & kFrameBitmap) {
    std::uint32_t k = 0;
    for (std::uint32_t byte = 0; byte < (n + 7) / 8 && in.ok; ++byte) {
      const auto bits = in.get<std::uint8_t>();
      for (int bit = 0; bit < 8; ++bit) {
        if (!(bits >> bit & 1)) continue;
        const std::uint32_t index = byte * 8 + static_cast<std::uint32_t>(bit);
        if (index >= n || k >= m) return false;
        f.bodies[k++].index = index;
      }
    }
    return in.ok && k == m;
  }
  for (std::uint32_t k = 0; k < m; ++k) {
    const auto index = in.get<std::uint32_t>();
    if (!in.ok || index >= n || (k > 0 && index <= f.bodies[k - 1].index)) return false;
    f.bodies[k].index = index;
  }
  return true;
}

void read_record(Reader& in, DecodedBody& d) {
  const auto format = in.get<std::uint8_t>();
  QuantBody& q = d.body;
  q.activity = format & 3u;
  d.absolute = (format & kRecordAbsolute) != 0;
  q.wide = (format & kRecordWide) != 0;
  q.exponent = static_cast<std::uint8_t>((format >> 4) + kMinAxisExponent);
  for (std::int32_t& c : q.centre) c = d.absolute ? in.get<std::int32_t>() : in.get<std::int16_t>();
  for (std::int32_t& a : q.axes) a = q.wide ? in.get<std::int32_t>() : in.get<std::int16_t>();
}

}  // namespace

std::optional<DecodedFrame> decode_frame(std::string_view bytes) {
  if (bytes.size() < kFrameHeaderBytes || bytes.substr(0, 4) != "TMBL") return std::nullopt;
  Reader in{bytes, 4};
  DecodedFrame f;
  f.version = in.get<std::uint16_t>();
  f.flags = in.get<std::uint16_t>();
  f.frame_number = in.get<std::uint32_t>();
  f.base_number = in.get<std::uint32_t>();
  f.body_count = in.get<std::uint32_t>();
  const auto m = in.get<std::uint32_t>();
  f.time = in.get<double>();
  f.energy = in.get<double>();
  // Every record is at least 7 bytes: a count beyond what the bytes can hold is refused
  // before anything is allocated for it.
  if (f.version != kFrameVersion || m > f.body_count || m > (bytes.size() - in.at) / 7)
    return std::nullopt;
  if (f.keyframe() && f.base_number != f.frame_number) return std::nullopt;
  if (f.body_count > bytes.size() * 8 && (f.flags & kFrameBitmap)) return std::nullopt;
  f.bodies.resize(m);
  if (!read_selection(in, f, m)) return std::nullopt;
  for (DecodedBody& d : f.bodies) {
    read_record(in, d);
    if (f.keyframe() && !d.absolute) return std::nullopt;
  }
  if (!in.ok || in.at != bytes.size()) return std::nullopt;
  return f;
}

bool FrameDecoder::apply(const DecodedFrame& frame) {
  if (!frame.keyframe()) {
    if (!last_ || last_->frame_number != frame.base_number ||
        bodies_.size() != frame.body_count)
      return false;
  } else {
    bodies_.assign(frame.body_count, QuantBody{});
  }
  for (const DecodedBody& d : frame.bodies) {
    QuantBody& q = bodies_[d.index];
    const std::array<std::int32_t, 3> before = q.centre;
    q = d.body;
    if (!d.absolute)
      for (int k = 0; k < 3; ++k)
        q.centre[k] = static_cast<std::int32_t>(static_cast<std::int64_t>(before[k]) + d.body.centre[k]);
  }
  last_ = frame;
  last_->bodies.clear();
  return true;
}

std::array<Vec3, 8> FrameDecoder::vertices(std::size_t b) const {
  std::array<Vec3, 8> v;
  for (int i = 0; i < 8; ++i) v[i] = quantised_vertex(bodies_.at(b), i);
  return v;
}

}  // namespace tumble::server
