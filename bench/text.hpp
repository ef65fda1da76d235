#pragma once
/// The prose of docs/benchmarks.md lives in Markdown templates under bench/text/ (one per
/// section, `{{name}}` placeholders), so that the C++ computes numbers and tables and the
/// words can be edited as Markdown. Pure functions apart from reading the template file.
#include <map>
#include <string>
#include <vector>

namespace tumble_bench {

/// Values for a template's placeholders, name → Markdown text.
using Fields = std::map<std::string, std::string>;

/// Reads bench/text/`name`.md and replaces every `{{key}}` with fields[key]. A placeholder
/// with no value throws std::runtime_error naming the template and the key, so that a
/// template and its caller cannot drift apart silently (the ctest `bench_quick` catches it).
std::string fill_template(const std::string& name, const Fields& fields);

/// Replaces `{{key}}` placeholders in `text` (the work of fill_template, for tests and for
/// templates already read); `where` names the text in the error message.
std::string fill_placeholders(const std::string& text, const Fields& fields,
                              const std::string& where);

/// "- a.\n- b.\n" from a list of items ("" for an empty list); each item gets a full stop.
std::string bullet_list(const std::vector<std::string>& items);

}  // namespace tumble_bench
