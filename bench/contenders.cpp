#include "contenders.hpp"

#include <chrono>
#include <cmath>

#include "common.hpp"
#include "scenes.hpp"
#include "tumble/world.hpp"

namespace tumble_bench {
namespace {

/// Tumble behind the peers' interface, so every engine is driven by the same loop.
class TumbleAsPeer final : public PeerWorld {
 public:
  TumbleAsPeer(const tumble::Scene& s, unsigned threads) : w_(s) { w_.set_threads(threads); }
  void step() override {
    w_.step();
    alone_ += w_.last_step().solo;
  }
  PeerBodyState state(std::size_t i) const override {
    const tumble::Body& b = w_.body(static_cast<tumble::BodyId>(i));
    return {b.s.x, Quat(b.s.R), tumble::velocity(b.s, b.c), tumble::angular_velocity(b.s, b.c)};
  }
  long awake_count() const override { return static_cast<long>(w_.awake_count()); }
  long long impacts() const override { return static_cast<long long>(w_.total_impacts()); }
  long steps_alone() const override { return alone_; }
  /// A zero impulse on every body every 15 steps wakes its island (Tumble has no switch to
  /// turn sleeping off; 15 steps is well below the 0.5 s sleep timer at dt = 1/60).
  void keep_awake(long step) override {
    if (step % 15 != 0) return;
    for (std::size_t i = 0; i < w_.bodies().size(); ++i)
      w_.apply_impulse(static_cast<tumble::BodyId>(i), tumble::Vec3::Zero());
  }

 private:
  tumble::World w_;
  long alone_ = 0;  // steps run on the calling thread alone (StepStats::solo)
};

Contender peer_contender(const PeerEngine& p) {
  const std::string note = p.name == "bullet" ? "DISABLE_DEACTIVATION on every body"
                           : p.name == "ode"  ? "auto-disable off"
                           : p.name == "box3d" ? "enableSleep off"
                                              : "no sleeping in MuJoCo 2.2: always awake";
  return {p.name,
          [make = p.make](const tumble::Scene& s, const PeerSetup& setup) {
            PeerScene ps = to_peer(s);
            ps.stacking = setup.stacking;
            ps.allow_sleep = setup.allow_sleep;
            return make(ps);
          },
          note, p.name.rfind("mujoco", 0) != 0};
}

Contender tumble_contender(unsigned threads) {
  return {threads == 1 ? "tumble" : "tumble-" + std::to_string(threads) + "t",
          [threads](const tumble::Scene& s, const PeerSetup&) {
            return std::make_unique<TumbleAsPeer>(s, threads);
          },
          "zero impulse on every body every 15 steps", true, threads};
}

}  // namespace

std::vector<Contender> contenders(bool with_rk4, unsigned tumble_threads) {
  std::vector<Contender> c;
  c.push_back(tumble_contender(1));
  if (tumble_threads > 1) c.push_back(tumble_contender(tumble_threads));
  for (const PeerEngine& p : available_peers()) c.push_back(peer_contender(p));
#ifdef TUMBLE_BENCH_HAVE_MUJOCO
  if (with_rk4) c.push_back(peer_contender(mujoco_peer(true)));
#else
  (void)with_rk4;
#endif
  return c;
}

double clock_of(const Contender& c) {
  if (c.threads <= 1) return thread_cpu_seconds();
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double timed_run(const Contender& c, const tumble::Scene& s, long steps,
                 std::unique_ptr<PeerWorld>* keep, std::string* why) {
  std::unique_ptr<PeerWorld> w;
  try {
    w = c.make(s, PeerSetup{});
  } catch (const std::exception& e) {
    if (why) *why = e.what();
    return NAN;
  }
  const double t0 = clock_of(c);
  for (long i = 0; i < steps; ++i) w->step();
  const double cpu = clock_of(c) - t0;
  if (keep) *keep = std::move(w);
  return cpu;
}

}  // namespace tumble_bench
