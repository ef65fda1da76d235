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

/// Rows of the constraint Jacobian per contact: 1 frictionless, 4 for a pyramidal condim-3 cone.
std::size_t rows_per_contact(int condim) { return condim == 1 ? 1 : 4; }

/// Bytes MuJoCo 2.2 allocates up front in mjData per constraint row for a model of nv dofs:
/// efc_J, efc_JT (mjtNum) and their column indices (int), nv each; efc_AR (mjtNum) and
/// efc_AR_colind (int), njmax each; about 20 short per-row arrays.
double bytes_for_rows(double rows, double nv) { return rows * (24.0 * nv + 12.0 * rows + 160.0); }

/// mjData's buffer size is an `int` in MuJoCo 2.2 (mjData::nbuffer): nothing beyond 2 GiB can
/// be allocated, whatever memory the machine has. We stay at 1.6e9 bytes for the constraint
/// arrays, leaving room for the contact array, the stack and the rest of mjData.
constexpr double kMaxConstraintBytes = 1.6e9;

/// nconmax / njmax for a scene, or a reason why it does not fit.
struct Capacity {
  std::size_t contacts = 0;  ///< nconmax.
  std::size_t rows = 0;      ///< njmax.
  std::string refused;       ///< Non-empty: the scene cannot run.
};

Capacity capacity_for(const PeerScene& scene) {
  const std::size_t n = scene.boxes.size();
  const int condim = scene.friction <= 0.0 ? 1 : 3;
  const std::size_t per = rows_per_contact(condim);
  const double nv = 6.0 * static_cast<double>(n);
  // Separated scenes: a box on the plane makes at most 4 contacts. Stacks and piles: a box
  // pair makes up to 8 (mjc_BoxBox), and a box in a pile touches several others, so we ask for
  // 24 contacts per box and take what MuJoCo 2.2's allocation allows.
  const std::size_t wanted = (scene.stacking ? 24 : 4) * n + 16;
  const std::size_t needed = 4 * n + 16;  // every box resting on 4 points
  Capacity c;
  c.contacts = wanted;
  while (c.contacts > needed &&
         bytes_for_rows(static_cast<double>(c.contacts * per), nv) > kMaxConstraintBytes)
    c.contacts = std::max(needed, c.contacts * 9 / 10);
  c.rows = c.contacts * per;
  const double bytes = bytes_for_rows(static_cast<double>(c.rows), nv);
  if (bytes > kMaxConstraintBytes) {
    char buf[700];
    std::snprintf(buf, sizeof buf,
                  "MuJoCo 2.2 allocates its constraint arrays densely and up front in mjData "
                  "(efc_AR and its column indices, njmax × njmax; efc_J/efc_JT, njmax × nv), and "
                  "mjData's buffer size is a C int (≤ 2 GiB); %zu boxes resting on 4 contact "
                  "points each need nconmax ≥ %zu, njmax ≥ %zu rows with nv = %.0f, i.e. %.1f GB "
                  "of constraint arrays, beyond what the int buffer can hold; a smaller "
                  "<size nconmax/njmax> would drop contacts once the boxes land "
                  "(mjWARN_CONTACTFULL / mjWARN_CNSTRFULL), so it would not be the same "
                  "simulation; MuJoCo 2.3 replaced these arrays with an arena (<size memory>)",
                  n, needed, needed * per, nv, bytes / 1e9);
    c.refused = buf;
  }
  return c;
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
    << "  <size nconmax=\"" << capacity_for(scene).contacts << "\" njmax=\""
    << capacity_for(scene).rows << "\"/>\n"
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

class MujocoWorld final : public PeerWorld {
 public:
  MujocoWorld(const PeerScene& scene, bool rk4) {
    const Capacity cap = capacity_for(scene);
    if (!cap.refused.empty()) throw std::runtime_error(cap.refused);
    nconmax_ = cap.contacts;
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

  std::string trouble() const override {
    const int contacts = data_->warning[mjWARN_CONTACTFULL].number;
    const int rows = data_->warning[mjWARN_CNSTRFULL].number;
    if (contacts == 0 && rows == 0) return {};
    return "contact buffer full in " + std::to_string(contacts) + " steps, constraint buffer " +
           "full in " + std::to_string(rows) + " steps (nconmax " + std::to_string(nconmax_) +
           "): contacts were dropped";
  }

 private:
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::size_t nconmax_ = 0;
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
              "MuJoCo 2.2 has no sleeping; <size nconmax njmax> 4 contacts per box + 16 for "
              "separated scenes; for stacks and piles 24 contacts per box + 16, lowered until "
              "the up-front constraint arrays fit mjData's int-sized buffer (≤ 1.6 GB for "
              "them), and the contact and constraint overflow warnings checked after the run",
          [rk4](const PeerScene& s) { return std::make_unique<MujocoWorld>(s, rk4); }};
}

}  // namespace tumble_bench
