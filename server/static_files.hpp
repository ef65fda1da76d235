#pragma once
/// Mapping request targets to files under the web root, refusing anything that could leave
/// it. Pure functions apart from reading the file system; thread-safe.
#include <filesystem>
#include <string_view>

namespace tumble::server {

/// Where a target leads.
struct StaticLookup {
  unsigned status = 200;          ///< 200, 400 (malformed), 403 (outside the root), 404.
  std::filesystem::path file;     ///< The regular file to send when status is 200.
};

/// Resolves `target` (the request target, query allowed) under `root` (canonical, absolute).
/// "/" and "…/" mean index.html. Refuses, after percent-decoding: "..", "." and empty
/// segments other than a trailing "/", backslashes, NUL, and any path (symlinks resolved)
/// that does not stay inside `root`. Directories are never listed (404).
StaticLookup resolve_static(const std::filesystem::path& root, std::string_view target);

/// Content-Type for a file by extension (.html, .js/.mjs, .css, .json, .svg, .png …).
std::string_view mime_type(const std::filesystem::path& file);

}  // namespace tumble::server
