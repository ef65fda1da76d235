#include "frame_state.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tumble::server {
namespace {

std::uint8_t activity_code(Activity a) {
  switch (a) {
    case Activity::awake: return 0;
    case Activity::asleep: return 1;
    case Activity::frozen: return 2;
  }
  return 0;
}

// The pose shown at `alpha` ∈ [0, 1] between the previous step (0) and the current one (1):
// centre of mass linearly, orientation by slerp, so boxes stay rigid.
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

std::int32_t round_clamped(double value, double scale) {
  constexpr double kMax = std::numeric_limits<std::int32_t>::max();
  return static_cast<std::int32_t>(std::clamp(std::nearbyint(value * scale), -kMax, kMax));
}

}  // namespace

void choose_axis_encoding(const Vec3& half_extents, QuantBody& body) {
  const double h = std::max(half_extents.maxCoeff(), 1e-9);
  const int narrow = static_cast<int>(std::floor(std::log2(32767.0 / h)));
  if (narrow >= kMinNarrowExponent) {
    body.wide = false;
    body.exponent = static_cast<std::uint8_t>(std::min(narrow, kMaxAxisExponent));
    return;
  }
  const int wide = static_cast<int>(std::floor(std::log2(2147483647.0 / h)));
  body.wide = true;
  body.exponent = static_cast<std::uint8_t>(std::clamp(wide, kMinAxisExponent, kMaxAxisExponent));
}

bool quantise_pose(const Vec3& x, const Mat3& R, const Vec3& half_extents, QuantBody& body) {
  if (!x.allFinite() || !R.allFinite()) return false;
  const double axis_scale = std::ldexp(1.0, body.exponent);
  for (int k = 0; k < 3; ++k) body.centre[k] = round_clamped(x[k], 1.0 / kCentreUnit);
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 3; ++k)
      body.axes[3 * a + k] = round_clamped(R(k, a) * half_extents[a], axis_scale);
  return true;
}

Vec3 quantised_vertex(const QuantBody& body, int i) {
  const double unit = std::ldexp(1.0, -body.exponent);
  Vec3 v;
  for (int k = 0; k < 3; ++k) {
    double offset = 0.0;
    for (int a = 0; a < 3; ++a)
      offset += ((i >> a) & 1 ? 1.0 : -1.0) * body.axes[3 * a + k];
    v[k] = body.centre[k] * kCentreUnit + offset * unit;
  }
  return v;
}

std::shared_ptr<const FrameState> make_frame_state(const Snapshot& s, std::uint32_t number,
                                                   double time, const FrameState* previous) {
  const std::vector<BodyPose>& poses = *s.bodies;
  const std::vector<BodyConstants>& constants = s.scene->constants;
  const std::size_t n = poses.size();
  auto state = std::make_shared<FrameState>();
  state->number = number;
  state->generation = s.scene->generation;
  state->flags = static_cast<std::uint16_t>((s.paused ? 1u : 0u) | (s.frozen > 0 ? 2u : 0u));
  state->time = time;
  state->energy = s.energy;
  const bool same = previous && previous->generation == state->generation &&
                    previous->bodies.size() == n;
  state->bodies.resize(n);
  state->changed_at.assign(n, number);
  state->last_change = same ? previous->last_change : number;

  const bool interpolate = s.previous_bodies && s.previous_bodies->size() == n &&
                           s.time > s.previous_time && time < s.time;
  const double alpha = interpolate ? (time - s.previous_time) / (s.time - s.previous_time) : 1.0;
  for (std::size_t b = 0; b < n; ++b) {
    QuantBody& q = state->bodies[b];
    const Vec3& half = b < constants.size() ? constants[b].half_extents : Vec3(0.5, 0.5, 0.5);
    if (same) q = previous->bodies[b];
    else choose_axis_encoding(half, q);
    const BodyState shown = shown_state(poses[b], interpolate ? &(*s.previous_bodies)[b] : nullptr,
                                        alpha);
    quantise_pose(shown.x, shown.R, half, q);  // Not finite: the last finite pose stays.
    q.activity = activity_code(poses[b].activity);
    if (same && q == previous->bodies[b]) state->changed_at[b] = previous->changed_at[b];
    else state->last_change = number;
  }
  return state;
}

}  // namespace tumble::server
