#pragma once
/// Sections of docs/benchmarks.md: each subcommand writes its Markdown section and a few
/// headline values into the results directory; the docs are assembled from whatever is there,
/// so a single subcommand re-run refreshes its part only.
#include <map>
#include <string>

#include "common.hpp"

namespace tumble_bench {

/// Section names in document order.
inline constexpr const char* kSections[] = {"work_precision", "stability", "throughput", "skip",
                                            "peers", "contact", "pile_precision",
                                            "stages"};

/// Writes `<out>/<name>.md`.
void write_section(const Options& o, const std::string& name, const std::string& markdown);

/// Records a headline value (merged into `<out>/summary.csv`, key → value).
void record_value(const Options& o, const std::string& key, const std::string& value);
/// Reads all recorded headline values.
std::map<std::string, std::string> recorded_values(const Options& o);

/// Markdown image link to a plot, relative to the docs file.
std::string image_link(const Options& o, const fs::path& svg, const std::string& alt);
/// Markdown link to a results file, relative to the docs file.
std::string file_link(const Options& o, const fs::path& file);

/// Assembles o.docs from the section files and the headline values (the closing note).
void assemble_docs(const Options& o, const std::string& command_line);

}  // namespace tumble_bench
