// World::contacts: the last step's contact points for viewers and tools.
#include <algorithm>

#include "floor_contact.hpp"
#include "pipeline.hpp"
#include "tumble/world.hpp"

namespace tumble {
namespace {

constexpr double kShownGap = 1e-4;     // m: a solved point farther apart is speculative
constexpr double kFloorTouch = 1e-6;   // m: a vertex this close to the floor touches it

}  // namespace

void World::contacts(std::vector<ContactView>& out) const {
  out.clear();
  std::vector<std::uint8_t> solved(bodies_.size(), 0);
  for (const Contact& c : cache_->previous) {
    for (int i = 0; i < c.count; ++i) {
      const ContactPoint& p = c.points[i];
      if (p.normal_impulse <= 0.0 && p.separation > kShownGap) continue;
      out.push_back({p.position, c.normal, p.normal_impulse,
                     c.a == kStaticBody ? kFloorBody : c.a, c.b, true});
    }
    if (c.a != kStaticBody) solved[c.a] = 1;
    solved[c.b] = 1;
  }
  if (!scene_.world.floor) return;
  const double floor_y = scene_.world.floor->height;
  const double weight_impulse = scene_.world.gravity.norm() * scene_.world.dt;
  for (std::uint32_t id = 0; id < bodies_.size(); ++id) {
    const Body& b = bodies_[id];
    if (solved[id] || b.activity == Activity::frozen) continue;
    if (lowest_vertex_y(b.s, b.c) - floor_y > kFloorTouch) continue;
    const std::size_t first = out.size();
    for (int v = 0; v < 8; ++v) {
      const Vec3 p = world_vertex(b.s, b.c, v);
      if (p.y() - floor_y <= kFloorTouch)
        out.push_back({p, Vec3::UnitY(), 0.0, kFloorBody, id, false});
    }
    const double share = b.c.mass * weight_impulse / static_cast<double>(out.size() - first);
    for (std::size_t k = first; k < out.size(); ++k) out[k].impulse = share;
  }
}

}  // namespace tumble
