#include "peers/peer.hpp"

namespace tumble_bench {

std::vector<PeerEngine> available_peers() {
  std::vector<PeerEngine> peers;
#ifdef TUMBLE_BENCH_HAVE_BULLET
  peers.push_back(bullet_peer());
#endif
#ifdef TUMBLE_BENCH_HAVE_ODE
  peers.push_back(ode_peer());
#endif
#ifdef TUMBLE_BENCH_HAVE_MUJOCO
  peers.push_back(mujoco_peer(false));
#endif
#ifdef TUMBLE_BENCH_HAVE_BOX3D
  peers.push_back(box3d_peer());
#endif
  return peers;
}

}  // namespace tumble_bench
