/// MuJoCo peer: each scene written as an MJCF string (free bodies with box geoms, a plane
/// turned to face +y), loaded through a temporary file, stepped with mj_step.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

#include "peers/peer.hpp"

namespace tumble_bench {
namespace {

/// Damping ratio of a linear spring–damper whose bounce has restitution e:
/// e = exp(−ζπ/√(1−ζ²)). MuJoCo's soft contact is not exactly linear, so this is approximate.
double damping_ratio_for(double e) {
  if (e <= 0.0) return 1.0;
  const double l = std::log(e);
  return -l / std::sqrt(std::numbers::pi * std::numbers::pi + l * l);
}

/// Contact time constant, s, for damping ratio zeta: max(0.02 s, 2·dt/ζ).
/// MuJoCo's documented rule is timeconst ≥ 2·timestep (default 0.02 s), and MuJoCo 2.2 already
/// enforces it (the `refsafe` flag, on by default), so it alone does not change anything: the
/// `bounce` cube still went to 5.4 m at dt = 1/60. The cause is the stiffness MuJoCo derives,
/// k = 1/(dmax²·τ²·ζ²): with ζ = 0.215 (e = 0.5) the contact oscillates at
/// ω₀ = 1/(dmax·τ·ζ) ≈ 147 rad/s, ω₀·dt ≈ 2.4 > 2, beyond what the semi-implicit Euler step
/// resolves, and the box gains energy. Applying the rule to the oscillation, τ·ζ ≥ 2·dt,
/// resolves it (apex 0.233 m against 0.25 m) and reduces to MuJoCo's rule for ζ = 1.
double contact_time_constant(double dt, double zeta) {
  return std::max(0.02, 2.0 * dt / std::max(zeta, 0.05));  // e → 1 makes ζ → 0
}

/// A box on a plane makes at most 4 contacts; MuJoCo 2.2 sizes mjData from these at load.
std::size_t contact_capacity(std::size_t bodies) { return 4 * bodies + 16; }
/// Constraint rows: 1 per frictionless contact, 4 per pyramidal condim-3 contact.
std::size_t constraint_rows(std::size_t bodies, int condim) {
  return contact_capacity(bodies) * (condim == 1 ? 1 : 4);
}

std::string mjcf(const PeerScene& scene, bool rk4) {
  std::ostringstream x;
  x.precision(17);
  const std::size_t n = scene.boxes.size();
  const bool frictionless = scene.friction <= 0.0;
  const int condim = frictionless ? 1 : 3;
  const double mu = frictionless ? 0.0 : scene.friction;
  const double zeta = damping_ratio_for(scene.restitution);
  x << "<mujoco model=\"tumble_bench\">\n"
    << "  <compiler angle=\"radian\" inertiafromgeom=\"true\"/>\n"
    << "  <option timestep=\"" << scene.dt << "\" gravity=\"" << scene.gravity.x() << ' '
    << scene.gravity.y() << ' ' << scene.gravity.z() << "\" integrator=\""
    << (rk4 ? "RK4" : "Euler") << "\"/>\n"
    << "  <size nconmax=\"" << contact_capacity(n) << "\" njmax=\""
    << constraint_rows(n, condim) << "\"/>\n"
    << "  <default><geom condim=\"" << condim << "\" friction=\"" << mu
    << " 0.005 0.0001\" solref=\"" << contact_time_constant(scene.dt, zeta) << ' ' << zeta
    << "\"/></default>\n"
    << "  <worldbody>\n";
  if (scene.floor) x << "    <geom name=\"floor\" type=\"plane\" size=\"0 0 1\" zaxis=\"0 1 0\"/>\n";
  for (std::size_t i = 0; i < n; ++i) {
    const PeerBox& b = scene.boxes[i];
    x << "    <body pos=\"" << b.position.x() << ' ' << b.position.y() << ' ' << b.position.z()
      << "\" quat=\"" << b.orientation.w() << ' ' << b.orientation.x() << ' '
      << b.orientation.y() << ' ' << b.orientation.z() << "\"><freejoint/>"
      << "<geom type=\"box\" size=\"" << b.size.x() / 2 << ' ' << b.size.y() / 2 << ' '
      << b.size.z() / 2 << "\" mass=\"" << b.mass << "\"/></body>\n";
  }
  x << "  </worldbody>\n</mujoco>\n";
  return x.str();
}

/// MuJoCo 2.2 allocates efc_J (njmax × nv) and efc_AR (njmax × njmax) densely.
double mujoco_dense_bytes(const PeerScene& scene) {
  const double n = static_cast<double>(scene.boxes.size());
  const double rows = static_cast<double>(
      constraint_rows(scene.boxes.size(), scene.friction <= 0.0 ? 1 : 3));
  return rows * 6.0 * n * 8.0 + rows * rows * 12.0;
}

/// Above this we refuse rather than take the shared machine's memory.
constexpr double kMaxGigabytes = 3.0;

class MujocoWorld final : public PeerWorld {
 public:
  MujocoWorld(const PeerScene& scene, bool rk4) {
    const double gb = mujoco_dense_bytes(scene) / 1e9;
    if (gb > kMaxGigabytes) {
      // <size njmax> cannot be lowered to fit: once the boxes land, every one of them holds
      // up to 4 floor contacts, and rows beyond njmax do not fit (MuJoCo warns
      // mjWARN_CNSTRFULL and drops constraints), so it would no longer be the same
      // simulation. The arena that removes this limit (<size memory>) arrived in MuJoCo 2.3.
      char buf[600];
      std::snprintf(buf, sizeof buf,
                    "MuJoCo 2.2 allocates efc_J (njmax × nv) and efc_AR (njmax × njmax) densely "
                    "in mjData; the scene needs njmax ≥ %zu constraint rows (up to 4 floor "
                    "contacts per box on the floor) with nv = %zu, i.e. %.0f GB, so it was not built "
                    "(limit %.0f GB on this shared machine); a smaller njmax in <size> is no way "
                    "out: the rows of the landed boxes would not fit (MuJoCo warns "
                    "mjWARN_CNSTRFULL and drops constraints), so it would not be the same "
                    "simulation; MuJoCo 2.3 replaced these arrays with an arena (<size memory>)",
                    constraint_rows(scene.boxes.size(), scene.friction <= 0.0 ? 1 : 3),
                    6 * scene.boxes.size(), gb, kMaxGigabytes);
      throw std::runtime_error(buf);
    }
    static std::atomic<int> counter{0};
    const std::filesystem::path path =
        std::filesystem::temp_directory_path() /
        ("tumble_bench_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".xml");
    {
      std::ofstream f(path);
      f << mjcf(scene, rk4);
    }
    char error[1000] = "";
    model_ = mj_loadXML(path.c_str(), nullptr, error, sizeof error);
    std::filesystem::remove(path);
    if (!model_) throw std::runtime_error(std::string("MuJoCo: ") + error);
    data_ = mj_makeData(model_);
    for (std::size_t i = 0; i < scene.boxes.size(); ++i) {
      const PeerBox& b = scene.boxes[i];
      // Free joint: linear velocity in the world frame, angular velocity in the body frame.
      const Vec3 w_local = b.orientation.conjugate() * b.angular_velocity;
      mjtNum* v = data_->qvel + 6 * i;
      for (int k = 0; k < 3; ++k) {
        v[k] = b.velocity[k];
        v[3 + k] = w_local[k];
      }
    }
    mj_forward(model_, data_);
  }
  ~MujocoWorld() override {
    mj_deleteData(data_);
    mj_deleteModel(model_);
  }

  void step() override { mj_step(model_, data_); }

  PeerBodyState state(std::size_t i) const override {
    const mjtNum* p = data_->qpos + 7 * i;
    const mjtNum* v = data_->qvel + 6 * i;
    PeerBodyState s;
    s.position = {p[0], p[1], p[2]};
    s.orientation = Quat(p[3], p[4], p[5], p[6]).normalized();
    s.velocity = {v[0], v[1], v[2]};
    s.angular_velocity = s.orientation * Vec3(v[3], v[4], v[5]);
    return s;
  }

  long awake_count() const override { return static_cast<long>(model_->nbody - 1); }

 private:
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
};

}  // namespace

PeerEngine mujoco_peer(bool rk4) {
  return {rk4 ? "mujoco-rk4" : "mujoco", mj_versionString(),
          std::string("mj_step with integrator=\"") + (rk4 ? "RK4" : "Euler") +
              "\" (Euler: MuJoCo's default semi-implicit Euler; RK4: its documented "
              "fourth-order option), free joints, box geoms with mass (inertia from geom), "
              "plane turned to +y; soft contacts, solref = (0.02 s, ζ) with ζ from e through "
              "e = exp(−ζπ/√(1−ζ²)) (MuJoCo has no restitution coefficient), condim 1 when "
              "frictionless else 3 with μ; Coriolis and centrifugal terms always included; "
              "MuJoCo 2.2 has no sleeping",
          [rk4](const PeerScene& s) { return std::make_unique<MujocoWorld>(s, rk4); }};
}

}  // namespace tumble_bench
