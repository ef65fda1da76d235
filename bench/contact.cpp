/// contact: box–box contact and stacking on Tumble and on the peers (Bullet, ODE, MuJoCo, those
/// found at build time), interleaved in one run: `tower` (10 boxes), `pyramid` (210) and `pile`
/// (1,000 dropped). Per scene and engine: CPU ms per step while every body is awake, drift of
/// the tower over 60 s kept awake, deepest penetration seen, time until everything sleeps;
/// Tumble's ratio to each peer.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <numeric>
#include <sstream>

#include "benchmarks.hpp"
#include "peers/peer.hpp"
#include "report.hpp"
#include "scenes.hpp"
#include "tumble/world.hpp"

namespace tumble_bench {
namespace {

/// An engine driven through the peers' interface, plus a way to keep it awake.
class Engine {
 public:
  virtual ~Engine() = default;
  virtual void step() = 0;
  virtual PeerBodyState state(std::size_t i) const = 0;
  virtual long awake_count() const = 0;
  virtual std::string trouble() const { return {}; }
  /// Called every step of a kept-awake run before step(): Tumble applies a zero impulse to
  /// every body every 15 steps (waking its island); peers are built with sleeping off instead.
  virtual void keep_awake(long /*step*/) {}
};

class TumbleEngine final : public Engine {
 public:
  explicit TumbleEngine(const tumble::Scene& s) : w_(s) {}
  void step() override { w_.step(); }
  PeerBodyState state(std::size_t i) const override {
    const tumble::Body& b = w_.body(static_cast<tumble::BodyId>(i));
    return {b.s.x, Quat(b.s.R), tumble::velocity(b.s, b.c), tumble::angular_velocity(b.s, b.c)};
  }
  long awake_count() const override { return static_cast<long>(w_.awake_count()); }
  void keep_awake(long step) override {
    if (step % 15 != 0) return;
    for (std::size_t i = 0; i < w_.bodies().size(); ++i)
      w_.apply_impulse(static_cast<tumble::BodyId>(i), tumble::Vec3::Zero());
  }

 private:
  tumble::World w_;
};

class PeerEngineAdapter final : public Engine {
 public:
  explicit PeerEngineAdapter(std::unique_ptr<PeerWorld> w) : w_(std::move(w)) {}
  void step() override { w_->step(); }
  PeerBodyState state(std::size_t i) const override { return w_->state(i); }
  long awake_count() const override { return w_->awake_count(); }
  std::string trouble() const override { return w_->trouble(); }

 private:
  std::unique_ptr<PeerWorld> w_;
};

struct Contender {
  std::string name;
  /// Builds the engine; `awake`: sleeping off (peers) / kept awake by the caller (Tumble).
  std::function<std::unique_ptr<Engine>(const tumble::Scene&, bool awake)> make;
  std::string sleep_note;  ///< How it is kept awake, or that it has no sleeping.
};

std::vector<Contender> contenders() {
  std::vector<Contender> c;
  c.push_back({"tumble",
               [](const tumble::Scene& s, bool) { return std::make_unique<TumbleEngine>(s); },
               "zero impulse on every body every 15 steps"});
  for (const PeerEngine& p : available_peers()) {
    std::string note = p.name == "bullet" ? "DISABLE_DEACTIVATION on every body"
                       : p.name == "ode"  ? "auto-disable off"
                                          : "no sleeping in MuJoCo 2.2: always awake";
    c.push_back({p.name,
                 [make = p.make](const tumble::Scene& s, bool awake) {
                   PeerScene ps = to_peer(s);
                   ps.stacking = true;
                   ps.allow_sleep = !awake;
                   return std::make_unique<PeerEngineAdapter>(make(ps));
                 },
                 note});
  }
  return c;
}

// ---- penetration, measured the same way for every engine from the states it reports -------

struct Box {
  Vec3 x;
  Eigen::Matrix3d R;  // columns: body axes in the world
  Vec3 h;             // half extents
  double radius;
};

/// Penetration depth of two boxes (m, > 0 when they overlap, else ≤ 0): the smallest overlap of
/// their projections over the 15 separating axes, which for two boxes is the exact minimum
/// translation distance.
double box_box_depth(const Box& a, const Box& b) {
  const Vec3 d = b.x - a.x;
  double depth = INFINITY;
  auto test = [&](Vec3 axis) {
    const double len = axis.norm();
    if (len < 1e-9) return;
    axis /= len;
    const double ra = (a.R.transpose() * axis).cwiseAbs().dot(a.h);
    const double rb = (b.R.transpose() * axis).cwiseAbs().dot(b.h);
    depth = std::min(depth, ra + rb - std::abs(d.dot(axis)));
  };
  for (int i = 0; i < 3; ++i) test(a.R.col(i));
  for (int i = 0; i < 3; ++i) test(b.R.col(i));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) test(a.R.col(i).cross(b.R.col(j)));
  return depth;
}

/// Deepest penetration (m, ≥ 0) between any two boxes and between any box and the floor y = 0.
double deepest_penetration(const Engine& e, const tumble::Scene& s) {
  const std::size_t n = s.bodies.size();
  std::vector<Box> boxes(n);
  double deepest = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const PeerBodyState st = e.state(i);
    const Vec3 h = s.bodies[i].size * 0.5;
    boxes[i] = {st.position, st.orientation.toRotationMatrix(), h, h.norm()};
    const double floor_y = s.world.floor ? s.world.floor->height : -INFINITY;
    deepest = std::max(deepest, floor_y - (st.position.y() - boxes[i].R.row(1).cwiseAbs().dot(h)));
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t i, std::size_t j) { return boxes[i].x.x() < boxes[j].x.x(); });
  for (std::size_t a = 0; a < n; ++a) {
    const Box& A = boxes[order[a]];
    for (std::size_t b = a + 1; b < n; ++b) {
      const Box& B = boxes[order[b]];
      if (B.x.x() - A.x.x() > A.radius + B.radius + 1.0) break;  // radii ≤ 0.87 m here
      if ((A.x - B.x).norm() > A.radius + B.radius) continue;
      deepest = std::max(deepest, box_box_depth(A, B));
    }
  }
  return deepest;
}

/// Largest |x − x₀| over the bodies.
double drift(const Engine& e, const std::vector<Vec3>& x0) {
  double d = 0.0;
  for (std::size_t i = 0; i < x0.size(); ++i) d = std::max(d, (e.state(i).position - x0[i]).norm());
  return d;
}

/// CPU seconds per step over `steps` steps of a fresh, kept-awake engine (building it is not
/// timed); stops early once `budget` CPU seconds are spent (*done: steps actually run).
double timed_awake(const Contender& c, const tumble::Scene& s, long steps, double budget,
                   long* done, std::string* why) {
  std::unique_ptr<Engine> e;
  try {
    e = c.make(s, true);
  } catch (const std::exception& ex) {
    *why = ex.what();
    return NAN;
  }
  double cpu = 0.0;
  long i = 1;
  for (; i <= steps && cpu < budget; ++i) {
    const double t0 = thread_cpu_seconds();
    e->keep_awake(i);
    e->step();
    cpu += thread_cpu_seconds() - t0;
  }
  *done = i - 1;
  const std::string t = e->trouble();
  if (!t.empty()) *why = t;
  return cpu / static_cast<double>(*done);
}

struct Behaviour {
  double penetration = NAN;  ///< Deepest seen, m.
  double drift = NAN;        ///< Largest |x − x₀| at the end, m.
  double end_time = NAN;     ///< Sim time of the end of the run, s.
  double asleep_at = NAN;    ///< Sim time when every body first slept (NaN: never/no sleeping).
  std::string trouble;
};

/// One untimed run: `awake` kept awake for `steps` steps, else sleeping as the engine does,
/// stopping once everything sleeps or after `budget` CPU seconds. Penetration sampled every
/// `every` steps.
Behaviour observe(const Contender& c, const tumble::Scene& s, long steps, bool awake, int every,
                  double budget) {
  Behaviour r;
  std::unique_ptr<Engine> e;
  try {
    e = c.make(s, awake);
  } catch (const std::exception& ex) {
    r.trouble = ex.what();
    return r;
  }
  std::vector<Vec3> x0;
  for (std::size_t i = 0; i < s.bodies.size(); ++i) x0.push_back(e->state(i).position);
  double deepest = 0.0;
  long i = 1;
  const double t0 = thread_cpu_seconds();
  for (; i <= steps; ++i) {
    if (thread_cpu_seconds() - t0 > budget) break;
    if (awake) e->keep_awake(i);
    e->step();
    if (i % every == 0) deepest = std::max(deepest, deepest_penetration(*e, s));
    if (!awake && e->awake_count() == 0) {
      r.asleep_at = static_cast<double>(i) * s.world.dt;
      break;
    }
  }
  r.penetration = deepest;
  r.drift = drift(*e, x0);
  r.end_time = static_cast<double>(std::min(i, steps + 1) - 1) * s.world.dt;
  if (std::isfinite(r.asleep_at)) r.end_time = r.asleep_at;
  r.trouble = e->trouble();
  return r;
}

/// Steps Tumble takes before any body sleeps (at most `cap`).
long steps_before_first_sleep(const tumble::Scene& s, long cap) {
  tumble::World w(s);
  for (long i = 1; i <= cap; ++i) {
    w.step();
    if (w.awake_count() < s.bodies.size()) return i - 1;
  }
  return cap;
}

struct SceneResult {
  std::string scene;
  long timed_steps = 0;
  std::map<std::string, std::vector<double>> ms;  // engine → per repetition
  std::map<std::string, long> steps_done;          // fewest steps timed (CPU budget)
  std::map<std::string, std::string> refused;
  std::map<std::string, Behaviour> tower_awake;   // 60 s kept awake (tower only)
  std::map<std::string, Behaviour> sleeping;      // until asleep / cap
};

}  // namespace

void run_contact(const Options& o) {
  const std::vector<Contender> engines = contenders();
  const int reps = o.quick ? 1 : std::max(3, o.repeats);
  struct Spec {
    std::string name;
    long sleep_cap;  // steps of the sleeping run
    int every;       // penetration sample period, steps
  };
  const std::vector<Spec> specs = {{"tower", o.quick ? 60 : 600, 1},
                                   {"pyramid", o.quick ? 60 : 600, 1},
                                   {"pile", o.quick ? 20 : 900, 5}};
  const long tower_steps = o.quick ? 60 : 3600;  // 60 s at dt = 1/60
  // CPU budget of one timed run and of one behaviour run, s: an engine that needs more is
  // timed over the steps it managed and its behaviour run ends early ("> t" in the table).
  const double budget = o.quick ? 0.5 : 25.0;
  const double behaviour_budget = o.quick ? 1.0 : 40.0;
  Progress bar("contact", specs.size() * (static_cast<std::size_t>(reps) + 1));
  std::vector<SceneResult> results;

  for (const Spec& spec : specs) {
    tumble::Scene s = bundled(spec.name);
    SceneResult r;
    r.scene = spec.name;
    // Timing window: the tower runs its whole 60 s kept awake; the pyramid and the pile the
    // first steps before Tumble puts anything to sleep (all engines the same steps).
    const long cap = spec.name == "tower" ? tower_steps : (o.quick ? 20 : 600);
    r.timed_steps = spec.name == "tower" ? tower_steps : steps_before_first_sleep(s, cap);
    if (r.timed_steps < 1) r.timed_steps = 1;
    for (int rep = 0; rep < reps; ++rep) {
      for (const Contender& c : engines) {
        if (r.refused.count(c.name) && r.refused[c.name].rfind("MuJoCo 2.2 allocates", 0) == 0)
          continue;  // refused at build: the same every time
        bar.note(spec.name + " " + c.name);
        std::string why;
        long done = 0;
        const double per_step = timed_awake(c, s, r.timed_steps, budget, &done, &why);
        if (!why.empty()) r.refused[c.name] = why;
        r.ms[c.name].push_back(per_step * 1e3);
        r.steps_done[c.name] =
            r.steps_done.count(c.name) ? std::min(r.steps_done[c.name], done) : done;
      }
      bar.tick();
    }
    for (const Contender& c : engines) {
      bar.note(spec.name + " " + c.name + " behaviour");
      if (spec.name == "tower") r.tower_awake[c.name] = observe(c, s, tower_steps, true, 1, behaviour_budget);
      r.sleeping[c.name] = observe(c, s, spec.sleep_cap, false, spec.every, behaviour_budget);
    }
    bar.tick();
    results.push_back(std::move(r));
  }

  // ---- CSV, plot, section.
  const fs::path csv = o.out / "contact.csv";
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> notes_extra;
  {
    Csv out(csv, {"scene", "scene_index", "engine", "engine_index", "bodies", "timed_steps",
                  "ms_per_step", "ratio_peer_over_tumble", "tower_drift_60s_m",
                  "max_penetration_m", "asleep_at_s", "sleeping_run_end_s", "note"});
    for (std::size_t si = 0; si < results.size(); ++si) {
      const SceneResult& r = results[si];
      const std::size_t n = bundled(r.scene).bodies.size();
      const double tumble_ms = median(r.ms.at("tumble"));
      double fastest = NAN;
      std::string fastest_name = "none";
      for (std::size_t ei = 0; ei < engines.size(); ++ei) {
        const std::string& name = engines[ei].name;
        const double ms = median(r.ms.at(name));
        const double ratio = ms / tumble_ms;
        const Behaviour& b = r.sleeping.at(name);
        const double tower_drift = r.scene == "tower" ? r.tower_awake.at(name).drift : NAN;
        // Deepest penetration: the sleeping run, and for the tower the 60 s awake run too.
        double pen = b.penetration;
        if (r.scene == "tower") pen = std::max(pen, r.tower_awake.at(name).penetration);
        const long done = r.steps_done.count(name) ? r.steps_done.at(name) : 0;
        const std::string timed_note =
            done > 0 && done < r.timed_steps
                ? "timed over its first " + std::to_string(done) + " of " +
                      std::to_string(r.timed_steps) + " steps (CPU budget " + fmt(budget) + " s)"
                : "";
        std::string note;
        if (r.refused.count(name)) note = r.refused.at(name);
        else if (!b.trouble.empty()) note = b.trouble;
        else if (r.scene == "tower" && !r.tower_awake.at(name).trouble.empty())
          note = r.tower_awake.at(name).trouble;
        const bool valid = std::isfinite(ms) && note.empty();
        std::string sleep_text;
        if (std::isfinite(b.asleep_at)) sleep_text = fmt(b.asleep_at) + " s";
        else if (engines[ei].sleep_note.rfind("no sleeping", 0) == 0) sleep_text = "no sleeping";
        else if (std::isfinite(b.end_time)) sleep_text = "> " + fmt(b.end_time) + " s";
        else sleep_text = "–";
        out.row() << r.scene << static_cast<long long>(si) << name << static_cast<long long>(ei)
                  << n << r.timed_steps << (valid || name == "tumble" ? ms : NAN)
                  << (name == "tumble" ? 1.0 : (valid ? ratio : NAN)) << tower_drift << pen
                  << b.asleep_at << b.end_time
                  << ("\"" + (note.empty() ? timed_note : note) + "\"");
        if (!timed_note.empty()) notes_extra.push_back("`" + r.scene + "` on " + name + ": " + timed_note);
        std::vector<std::string> row{"`" + r.scene + "`", name,
                                     std::isfinite(ms) && valid ? fmt(ms) : "did not run",
                                     name == "tumble" ? "1"
                                     : valid          ? fmt(ratio) + "×"
                                                      : "–",
                                     r.scene == "tower" && std::isfinite(tower_drift)
                                         ? fmt(tower_drift) + " m"
                                         : "–",
                                     std::isfinite(pen) ? fmt(pen) + " m" : "–", sleep_text};
        rows.push_back(row);
        if (name != "tumble" && valid && !(ms >= fastest)) {
          fastest = ms;
          fastest_name = name;
        }
        std::cerr << "  " << r.scene << " " << name << ": " << fmt(ms) << " ms/step"
                  << (name == "tumble" ? "" : ", peer/Tumble " + fmt(ratio))
                  << ", penetration " << fmt(pen) << " m, asleep " << sleep_text
                  << (r.scene == "tower" ? ", drift " + fmt(tower_drift) + " m" : "")
                  << (note.empty() ? "" : " [" + note.substr(0, 100) + "]") << '\n';
      }
      const std::string k = "contact." + r.scene + ".";
      record_value(o, k + "tumble_ms", fmt(tumble_ms, 4));
      record_value(o, k + "fastest_peer", fastest_name);
      record_value(o, k + "ratio_to_fastest", fmt(fastest / tumble_ms, 4));
      record_value(o, k + "tumble_penetration_m", fmt(r.sleeping.at("tumble").penetration, 4));
      record_value(o, k + "tumble_asleep_s", fmt(r.sleeping.at("tumble").asleep_at, 4));
      if (r.scene == "tower")
        record_value(o, k + "tumble_drift_60s_m", fmt(r.tower_awake.at("tumble").drift, 4));
    }
  }

  std::ostringstream g;
  g << "set logscale y\nset title 'box–box contact: CPU ms per step while every body is awake'\n"
    << "set ylabel 'CPU ms per step'\nset xrange [-0.6:" << results.size() - 0.4 << "]\n"
    << "set xtics (";
  for (std::size_t i = 0; i < results.size(); ++i)
    g << (i ? ", " : "") << "'" << results[i].scene << " (" << bundled(results[i].scene).bodies.size()
      << ")' " << i;
  g << ")\nset key top left\nset boxwidth " << 0.8 / static_cast<double>(engines.size())
    << "\nset style fill solid 0.8\nset datafile separator ','\nplot ";
  for (std::size_t ei = 0; ei < engines.size(); ++ei) {
    const double off = (static_cast<double>(ei) - (engines.size() - 1) / 2.0) * 0.8 /
                       static_cast<double>(engines.size());
    g << (ei ? ", \\\n     " : "") << "'contact.csv' skip 1 using (strcol(3) eq '"
      << engines[ei].name << "' ? $2 + (" << off << ") : 1/0):7 with boxes title '"
      << engines[ei].name << "'";
  }
  const fs::path svg = plot(o, "contact", g.str());

  const auto recorded = recorded_values(o);
  auto value = [&](const std::string& k) {
    const auto it = recorded.find(k);
    return it == recorded.end() ? std::string("unknown") : it->second;
  };
  std::ostringstream md;
  md << "## Contact\n\n"
     << "Measured on " << value("date") << " at engine commit " << value("engine_commit")
     << " by `tumble-bench contact" << (o.quick ? " --quick" : "") << "`.\n\n"
     << "Box–box contact and stacking on every engine: the bundled `tower` (10 unit cubes), "
        "`pyramid` (base 20, 210 cubes) and `pile` (1,000 boxes dropped from a grid) scenes, "
        "dt = 1/60 s, e and μ as each scene says (for every pair). Peers are built with their "
        "stacking settings (listed in the Peers section; ODE adds its demo_boxstack CFM and "
        "correcting-velocity cap, Bullet gets √e and √μ on each side so pairs get e and μ, "
        "MuJoCo gets larger contact buffers).\n\n"
     << "- **ms per step**: median CPU time of the stepping over " << reps
     << " interleaved repetitions (each repetition runs every engine in turn on a fresh "
        "world), with every body awake: Tumble gets a zero impulse on every body every 15 "
        "steps; ";
  for (const Contender& c : engines)
    if (c.name != "tumble") md << c.name << ": " << c.sleep_note << "; ";
  md << "timed steps: ";
  for (std::size_t i = 0; i < results.size(); ++i)
    md << (i ? ", " : "") << "`" << results[i].scene << "` " << results[i].timed_steps;
  md << " (the tower its whole 60 s; the pyramid and the pile the steps before Tumble puts "
        "anything to sleep, the same steps on every engine). Ratio = peer time / Tumble time "
        "(> 1: Tumble faster).\n"
     << "- **tower drift**: largest |x − x₀| over the ten boxes after 60 s kept awake as "
        "above.\n"
     << "- **max penetration**: deepest box–box or box–floor overlap, computed the same way "
        "for every engine from the poses it reports (15-axis separating-axis depth), sampled "
        "every step (every 5 steps in the pile) over the tower's 60 s awake run and the "
        "sleeping run below.\n"
     << "- **asleep at**: a second run with each engine's own sleeping, until every body "
        "sleeps (cap: tower and pyramid " << fmt(specs[0].sleep_cap / 60.0) << " s, pile "
     << fmt(specs[2].sleep_cap / 60.0)
     << " s, and at most " << fmt(behaviour_budget) << " s of CPU per run); \"> t\" means it "
        "was not asleep after t s of sim time.\n\n"
     << image_link(o, svg, "contact: ms per step on every engine") << "\n\n"
     << md_table({"scene", "engine", "ms per step", "ratio", "tower drift (60 s)",
                  "max penetration", "asleep at"},
                 rows)
     << "\nCSV: " << file_link(o, csv) << ".\n\n";
  std::vector<std::string> notes = notes_extra;
  for (const SceneResult& r : results)
    for (const auto& [name, why] : r.refused) notes.push_back("`" + r.scene + "` on " + name + ": " + why);
  for (const SceneResult& r : results)
    for (const auto& [name, b] : r.sleeping)
      if (!b.trouble.empty() && !r.refused.count(name))
        notes.push_back("`" + r.scene + "` on " + name + " (sleeping run): " + b.trouble);
  if (!notes.empty()) {
    md << "Not run or not valid:\n\n";
    for (const std::string& n : notes) md << "- " << n << ".\n";
    md << '\n';
  }
  write_section(o, "contact", md.str());
}

}  // namespace tumble_bench
