#pragma once
/// Shared plumbing of tumble-bench: options, a progress bar on stderr, CPU timers, memory
/// readings, CSV files and gnuplot. Not thread-safe (the bench is single-threaded).
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

namespace tumble_bench {

/// Short name for std::filesystem.
namespace fs = std::filesystem;

/// Command-line options shared by every subcommand.
struct Options {
  bool quick = false;  ///< Short version of everything (< 60 s in all), for ctest.
  fs::path out;        ///< Results directory (CSV, gnuplot scripts, SVG, section markdown).
  fs::path docs;       ///< Markdown file assembled from the sections.
  bool plots = true;   ///< Run gnuplot.
  int repeats = 3;     ///< Interleaved repetitions for timings (median taken).
  unsigned threads = 1;  ///< `contact`: also time Tumble on this many threads (when above 1).
  /// `contact` and `stages`: run only these scenes (empty: all), e.g. {"pyramid_large"}. The
  /// section then says it is a partial run.
  std::vector<std::string> only;
};

/// A progress bar on stderr: "label [#####.....]  45%  9/20  3.1 s". Redraws at most 10×/s on
/// a terminal; into a file, one line every 10 s at most.
class Progress {
 public:
  /// Draws an empty bar for `total` units of work.
  Progress(std::string label, std::size_t total);
  /// Draws the full bar and ends its line.
  ~Progress();
  Progress(const Progress&) = delete;             ///< One bar per stderr line.
  Progress& operator=(const Progress&) = delete;  ///< One bar per stderr line.
  /// Marks n more units done.
  void tick(std::size_t n = 1);
  /// Changes the note printed after the bar ("dt = 1/240").
  void note(std::string text);

 private:
  void draw(bool force);
  std::string label_;
  std::string note_;
  std::size_t total_;
  std::size_t done_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  bool tty_;
};

/// CPU time of the calling thread, s (immune to other processes taking the core).
double thread_cpu_seconds();
/// Wall-clock time, s.
double wall_seconds();
/// Resident set size now, bytes (VmRSS), 0 if unknown.
std::uint64_t resident_bytes();
/// Peak resident set size since the last reset_peak_resident(), bytes (VmHWM).
std::uint64_t peak_resident_bytes();
/// Resets VmHWM (writes 5 to /proc/self/clear_refs); false if the kernel refused.
bool reset_peak_resident();

/// True when `name` is selected by o.only (always, when o.only is empty).
bool selected(const Options& o, const std::string& name);
/// " (only `a`, `b`)" for a partial run, "" for a full one: for section headers.
std::string partial_note(const Options& o);

/// Median of a non-empty list.
double median(std::vector<double> v);

/// "1.23e-05"-style formatting with `digits` significant digits.
std::string fmt(double v, int digits = 3);
/// Fixed-point formatting.
std::string fixed(double v, int decimals);
/// "1/240" when dt is the reciprocal of an integer, else fmt(dt).
std::string dt_label(double dt);

/// A CSV file with a header line; values written with 17 significant digits.
class Csv {
 public:
  /// Opens `path` and writes the header line.
  Csv(const fs::path& path, std::initializer_list<std::string> columns);
  /// Same, with columns known only at run time.
  Csv(const fs::path& path, const std::vector<std::string>& columns);
  /// Starts a new row.
  Csv& row();
  /// Appends one cell to the current row.
  Csv& operator<<(const std::string& cell);
  Csv& operator<<(const char* cell);  ///< A text cell.
  Csv& operator<<(double v);          ///< 17 significant digits; "nan", "inf".
  Csv& operator<<(long long v);       ///< An integer cell.
  Csv& operator<<(int v) { return *this << static_cast<long long>(v); }
  Csv& operator<<(long v) { return *this << static_cast<long long>(v); }
  Csv& operator<<(std::size_t v) { return *this << static_cast<long long>(v); }
  /// Ends the last line.
  ~Csv();

 private:
  std::ofstream f_;
  bool first_cell_ = true;
  bool any_row_ = false;
};

/// Writes `name`.gp into dir (SVG terminal and output prepended) and runs gnuplot there.
/// Returns the SVG path (even when gnuplot is missing, so the docs stay stable).
fs::path plot(const Options& o, const std::string& name, const std::string& script);

/// A Markdown table.
std::string md_table(const std::vector<std::string>& header,
                     const std::vector<std::vector<std::string>>& rows);

}  // namespace tumble_bench
