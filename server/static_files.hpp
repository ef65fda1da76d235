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
  std::filesystem::path relative; ///< `file` relative to the root (symlink-free when checked).
};

/// A file opened for sending: `fd` (owned by the caller) when status is 200, else -1.
struct OpenedFile {
  int fd = -1;                    ///< Read-only descriptor of a regular file.
  unsigned status = 404;          ///< 200, 403 (it would leave the root), 404.
};

/// Resolves `target` (the request target, query allowed) under `root` (canonical, absolute).
/// "/" and "…/" mean index.html. Refuses, after percent-decoding: "..", "." and empty
/// segments other than a trailing "/", backslashes, NUL, and any path (symlinks resolved)
/// that does not stay inside `root`, dotfiles (any segment starting with '.') and anything
/// under node_modules but the files the page imports (403). Directories are never listed (404).
StaticLookup resolve_static(const std::filesystem::path& root, std::string_view target);

/// Opens `relative` (resolve_static's canonical path, so without symlinks when it was checked)
/// beneath the directory `root_fd` with openat2(RESOLVE_BENEATH | RESOLVE_NO_SYMLINKS), or,
/// where the kernel lacks openat2, one component at a time with O_NOFOLLOW. Symlinks inside
/// the root still work (resolve_static followed them); what is opened follows none, so a
/// file or directory swapped for a symlink after the check is refused (403), not served: no
/// check-then-open race. Only regular files are returned. Thread-safe.
OpenedFile open_beneath(int root_fd, const std::filesystem::path& relative);

/// Content-Type for a file by extension (.html, .js/.mjs, .css, .json, .svg, .png …).
std::string_view mime_type(const std::filesystem::path& file);

}  // namespace tumble::server
