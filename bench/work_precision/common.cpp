/// work-precision: what the three scenes share (step sizes, timing, plots, method names).
#include <sstream>

#include "tumble/world.hpp"
#include "work_precision/work_precision.hpp"

namespace tumble_bench::wp {

namespace {
constexpr double kFloorForLog = 1e-17;  // errors of exactly 0 are drawn here on log axes
}  // namespace

std::vector<double> step_sizes(bool quick) {
  std::vector<double> dts;
  const int n = quick ? 4 : 9;  // 1/15 … 1/3840 (quick: … 1/120)
  for (int k = 0; k < n; ++k) dts.push_back(1.0 / (15.0 * std::pow(2.0, k)));
  return dts;
}

double time_run(const tumble::Scene& scene, long steps, double budget) {
  double total = 0.0;
  int reps = 0;
  do {
    tumble::World w(scene);
    const double t0 = thread_cpu_seconds();
    for (long i = 0; i < steps; ++i) w.step();
    total += thread_cpu_seconds() - t0;
    ++reps;
  } while (total < budget && reps < 50);
  return total / reps;
}

std::string log_plot(const std::string& csv, const std::string& xlabel, const std::string& ylabel,
                     int xcol, int ycol, const std::vector<std::string>& curves, int keycol,
                     const std::string& title) {
  std::ostringstream g;
  g << "set logscale xy\nset format y '10^{%L}'\nset format x '10^{%L}'\n"
    << "set title '" << title << "'\nset xlabel '" << xlabel << "'\nset ylabel '" << ylabel
    << "'\n"
    << "plot ";
  for (std::size_t i = 0; i < curves.size(); ++i) {
    g << (i ? ", \\\n     " : "") << "'" << csv << "' skip 1 using (strcol(" << keycol
      << ") eq '" << curves[i] << "' ? $" << xcol << " : 1/0):(max($" << ycol << ", "
      << kFloorForLog << ")) with linespoints lw 1.5 title '" << curves[i] << "'";
  }
  return "max(a,b) = a > b ? a : b\n" + g.str();
}

std::string combo_name(tumble::Integrator integrator, tumble::ToiMethod toi) {
  return std::string(tumble::to_string(integrator)) + "+" + std::string(tumble::to_string(toi));
}

std::vector<std::string> combo_names() {
  std::vector<std::string> names;
  for (tumble::Integrator i : tumble::kIntegrators)
    for (tumble::ToiMethod t : kToiMethods) names.push_back(combo_name(i, t));
  return names;
}

}  // namespace tumble_bench::wp
