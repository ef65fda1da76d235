#pragma once
/// work-precision: error against CPU time, one curve per integrator (and TOI method), on
/// `tumble` (orientation, energy, |L| against an odeint reference), `bounce` (apexes and impact
/// times against the analytic values) and `seed` with e = 1 (final state against an
/// event-located odeint reference, energy drift). Each scene in measure (plain structs), record
/// (CSV, headline values, plots) and report (bench/text/work_precision_<scene>.md).
/// Single-threaded.
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "common.hpp"
#include "tumble/body.hpp"
#include "tumble/scene.hpp"

namespace tumble_bench::wp {

/// dt = 1/15 · 2^-k: 1/15 … 1/3840 s (--quick: … 1/120 s).
std::vector<double> step_sizes(bool quick);
/// CPU seconds of one run of `steps` steps (mean over as many repeats as fit in `budget`
/// CPU seconds, at most 50).
double time_run(const tumble::Scene& scene, long steps, double budget);
/// A gnuplot script: log–log, one curve per value of column `keycol`, y clamped to 1e-17.
std::string log_plot(const std::string& csv, const std::string& xlabel, const std::string& ylabel,
                     int xcol, int ycol, const std::vector<std::string>& curves, int keycol,
                     const std::string& title);
/// The TOI methods compared on the scenes with impacts.
inline constexpr std::array<tumble::ToiMethod, 2> kToiMethods{tumble::ToiMethod::bisection,
                                                              tumble::ToiMethod::root};
/// "exact+root".
std::string combo_name(tumble::Integrator integrator, tumble::ToiMethod toi);
/// Every integrator+TOI name, in table order.
std::vector<std::string> combo_names();

/// The files record() wrote for one scene.
struct Plots {
  fs::path csv;               ///< The scene's CSV.
  std::vector<fs::path> svg;  ///< Its plots, in the order the report shows them.
};

// ---- tumble

/// One integrator at one dt on `tumble`.
struct TumbleRun {
  std::string integrator;  ///< Integrator name.
  double dt = NAN;         ///< s.
  long steps = 0;          ///< Steps of the 20 s run.
  double cpu = NAN;        ///< CPU s per run.
  double angle = NAN;      ///< Geodesic orientation error at 20 s, rad.
  double e_rel = NAN;      ///< Relative energy error at 20 s.
  double l_rel = NAN;      ///< Relative |L| error at 20 s.
  double e_max = NAN;      ///< Largest relative energy error over the run.
};

/// `tumble` on every integrator and dt.
struct TumbleMeasurement {
  double ref_half = NAN;       ///< Reference vs itself at half the tolerance, rad.
  double ref_bs = NAN;         ///< Reference vs long-double Bulirsch–Stoer, rad.
  std::vector<TumbleRun> runs; ///< Integrator-major, dt decreasing.
};

/// Runs `tumble`; writes nothing.
TumbleMeasurement measure_tumble(const Options& o, Progress& bar);
/// Writes wp_tumble.csv, its headline values and three plots.
Plots record_tumble(const Options& o, const TumbleMeasurement& m);
/// The `tumble` subsection (bench/text/work_precision_tumble.md filled in).
std::string report_tumble(const Options& o, const TumbleMeasurement& m, const Plots& p);

// ---- bounce

/// The analytic bounces of the `bounce` scene.
struct BounceAnalytic {
  double h0 = NAN, e = NAN, g = NAN;    ///< Drop height of the lowest face (m), e, g (m/s²).
  double toi_tolerance = NAN;           ///< The scene's TOI tolerance, s.
  std::array<double, 3> t_impact{};     ///< Impact times, s.
  std::array<double, 3> apex{};         ///< Apex heights e^{2k}·h₀, m.
  double t_end = NAN;                   ///< End of the runs (past the third apex), s.
};

/// One integrator+TOI at one dt on `bounce`.
struct BounceRun {
  std::string method;                   ///< "exact+root".
  double dt = NAN;                      ///< s.
  long steps = 0;                       ///< Steps per run.
  double cpu = NAN;                     ///< CPU s per run.
  double apex_err = NAN;                ///< Worst of the three apex errors, m.
  double t_err = NAN;                   ///< Worst of the three impact-time errors, s.
  double apex1_err = NAN;               ///< First apex error, m.
  std::array<double, 3> apex{NAN, NAN, NAN};  ///< Apexes measured, m.
};

/// `bounce` on every integrator, TOI method and dt.
struct BounceMeasurement {
  BounceAnalytic a;              ///< The analytic answer.
  std::vector<BounceRun> runs;   ///< Method-major, dt decreasing.
  double worst_apex1_exact_root = 0.0;  ///< Worst first-apex error of exact+root, m.
};

/// Runs `bounce`; writes nothing.
BounceMeasurement measure_bounce(const Options& o, Progress& bar);
/// Writes wp_bounce.csv, its headline value and two plots.
Plots record_bounce(const Options& o, const BounceMeasurement& m);
/// The `bounce` subsection (bench/text/work_precision_bounce.md filled in).
std::string report_bounce(const Options& o, const BounceMeasurement& m, const Plots& p);

// ---- seed

/// State of the event-driven reference of one box on a frictionless floor.
struct SeedReference {
  tumble::Vec3 x, v, L;  ///< Centre (m), velocity (m/s), angular momentum (N·m·s).
  tumble::Mat3 R;        ///< Attitude.
  int impacts = 0;       ///< Impacts so far.
};

/// Event-driven reference for one box on a frictionless floor: exact parabola for the centre,
/// `tumble_reference` (RKF78 at `tol`) for the attitude, impacts located by TOMS 748 on the
/// lowest vertex, answered with the single-vertex impulse j = −(1+e) v_n / (1/m + n·(I⁻¹(r×n))×r).
SeedReference seed_reference(const tumble::Body& b, const tumble::Vec3& gravity, double e,
                             double t_end, double tol);

/// One integrator+TOI at one dt on `seed`.
struct SeedRun {
  std::string method;      ///< "exact+root".
  double dt = NAN;         ///< s.
  long steps = 0;          ///< Steps per run.
  double cpu = NAN;        ///< CPU s per run.
  double dx = NAN;         ///< Final position error, m.
  double da = NAN;         ///< Final orientation error, rad.
  double de = NAN;         ///< Relative energy drift at the end.
  long long impacts = 0;   ///< World::total_impacts() at the end.
};

/// `seed` on every integrator, TOI method and dt.
struct SeedMeasurement {
  double e = NAN, t_end = NAN;  ///< Restitution; simulated time, s.
  int ref_impacts = 0;          ///< Impacts in the reference.
  double ref_dx = NAN;          ///< Reference vs itself at half the tolerance: position, m.
  double ref_da = NAN;          ///< … and attitude, rad.
  std::vector<SeedRun> runs;    ///< Method-major, dt decreasing.
};

/// Runs `seed`; writes nothing.
SeedMeasurement measure_seed(const Options& o, Progress& bar);
/// Writes wp_seed.csv and two plots.
Plots record_seed(const Options& o, const SeedMeasurement& m);
/// The `seed` subsection (bench/text/work_precision_seed.md filled in).
std::string report_seed(const Options& o, const SeedMeasurement& m, const Plots& p);

}  // namespace tumble_bench::wp
