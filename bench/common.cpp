#include "common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <sstream>

namespace tumble_bench {

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(std::max<std::size_t>(total, 1)),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_),
      tty_(::isatty(2) != 0) {
  draw(true);
}

Progress::~Progress() {
  done_ = total_;
  draw(true);
  std::fputc('\n', stderr);
}

void Progress::tick(std::size_t n) {
  done_ = std::min(total_, done_ + n);
  draw(false);
}

void Progress::note(std::string text) {
  note_ = std::move(text);
  draw(false);
}

void Progress::draw(bool force) {
  const auto now = std::chrono::steady_clock::now();
  // A terminal is redrawn in place up to 10×/s; a log file gets a line every 10 s at most.
  if (!force && now - last_draw_ < std::chrono::milliseconds(tty_ ? 100 : 10000)) return;
  last_draw_ = now;
  constexpr int kWidth = 30;
  const double f = static_cast<double>(done_) / static_cast<double>(total_);
  const int filled = static_cast<int>(f * kWidth);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(kWidth, '.');
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::fprintf(stderr, "%s%-22s [%s] %3d%%  %zu/%zu  %6.1f s  %-24.24s", tty_ ? "\r" : "",
               label_.c_str(), bar.c_str(), static_cast<int>(f * 100.0), done_, total_, elapsed,
               note_.c_str());
  if (!tty_ && done_ < total_) std::fputc('\n', stderr);
  std::fflush(stderr);
}

double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

namespace {
std::uint64_t status_field_kb(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::string k = std::string(key) + ":";
  while (std::getline(f, line)) {
    if (line.rfind(k, 0) == 0) return std::strtoull(line.c_str() + k.size(), nullptr, 10);
  }
  return 0;
}
}  // namespace

std::uint64_t resident_bytes() { return status_field_kb("VmRSS") * 1024; }
std::uint64_t peak_resident_bytes() { return status_field_kb("VmHWM") * 1024; }

bool reset_peak_resident() {
  std::ofstream f("/proc/self/clear_refs");
  if (!f) return false;
  f << "5";
  f.flush();
  return static_cast<bool>(f);
}

bool selected(const Options& o, const std::string& name) {
  return o.only.empty() || std::find(o.only.begin(), o.only.end(), name) != o.only.end();
}

std::string partial_note(const Options& o) {
  if (o.only.empty()) return "";
  std::string s;
  for (const std::string& n : o.only) s += (s.empty() ? "`" : ", `") + n + "`";
  return ", a partial run with `--only` (" + s + " only)";
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string fmt(double v, int digits) {
  if (std::isnan(v)) return "n/a";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[64];
  const double a = std::fabs(v);
  if (a != 0.0 && (a < 1e-3 || a >= 1e5)) {
    std::snprintf(buf, sizeof buf, "%.*e", std::max(0, digits - 1), v);
  } else {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  }
  return buf;
}

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return fmt(v);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string dt_label(double dt) {
  const double r = 1.0 / dt;
  if (std::fabs(r - std::round(r)) < 1e-9 * r) return "1/" + std::to_string(std::lround(r));
  return fmt(dt);
}

Csv::Csv(const fs::path& path, std::initializer_list<std::string> columns)
    : Csv(path, std::vector<std::string>(columns)) {}

Csv::Csv(const fs::path& path, const std::vector<std::string>& columns) : f_(path) {
  f_.precision(17);
  bool first = true;
  for (const std::string& c : columns) {
    f_ << (first ? "" : ",") << c;
    first = false;
  }
}

Csv& Csv::row() {
  f_ << '\n';
  any_row_ = true;
  first_cell_ = true;
  return *this;
}

Csv& Csv::operator<<(const std::string& cell) {
  const bool quote = cell.find_first_of(",\"") != std::string::npos;
  f_ << (first_cell_ ? "" : ",");
  if (quote) {
    f_ << '"';
    for (char ch : cell) f_ << (ch == '"' ? "\"\"" : std::string(1, ch));
    f_ << '"';
  } else {
    f_ << cell;
  }
  first_cell_ = false;
  return *this;
}

Csv& Csv::operator<<(const char* cell) { return *this << std::string(cell); }

Csv& Csv::operator<<(double v) {
  f_ << (first_cell_ ? "" : ",");
  if (std::isfinite(v)) {
    f_ << v;
  } else {
    f_ << (std::isnan(v) ? "nan" : (v > 0 ? "inf" : "-inf"));
  }
  first_cell_ = false;
  return *this;
}

Csv& Csv::operator<<(long long v) {
  f_ << (first_cell_ ? "" : ",") << v;
  first_cell_ = false;
  return *this;
}

Csv::~Csv() { f_ << '\n'; }

fs::path plot(const Options& o, const std::string& name, const std::string& script) {
  const fs::path svg = o.out / (name + ".svg");
  const fs::path gp = o.out / (name + ".gp");
  {
    std::ofstream f(gp);
    f << "# Generated by tumble-bench; run `gnuplot " << name << ".gp` in this directory.\n"
      << "set terminal svg size 760,500 dynamic enhanced font 'Helvetica,12' background "
         "rgb 'white'\n"
      << "set output '" << name << ".svg'\n"
      << "set datafile separator ','\n"
      << "set key outside right top\n"
      << "set grid\n"
      << script << '\n';
  }
  if (o.plots) {
    const std::string cmd = "cd '" + o.out.string() + "' && gnuplot '" + name +
                            ".gp' 2> '" + name + ".gnuplot.log'";
    if (std::system(cmd.c_str()) != 0) {
      std::cerr << "gnuplot failed for " << gp << " (see " << name << ".gnuplot.log)\n";
    } else {
      std::error_code ec;
      fs::remove(o.out / (name + ".gnuplot.log"), ec);
    }
  }
  return svg;
}

std::string md_table(const std::vector<std::string>& header,
                     const std::vector<std::vector<std::string>>& rows) {
  std::ostringstream s;
  s << '|';
  for (const auto& h : header) s << ' ' << h << " |";
  s << "\n|";
  for (std::size_t i = 0; i < header.size(); ++i) s << (i == 0 ? "---|" : "---:|");
  s << '\n';
  for (const auto& r : rows) {
    s << '|';
    for (const auto& c : r) s << ' ' << c << " |";
    s << '\n';
  }
  return s.str();
}

}  // namespace tumble_bench
