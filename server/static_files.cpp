#include "static_files.hpp"

#include <fcntl.h>
#include <linux/openat2.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <optional>
#include <string>

namespace tumble::server {
namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::optional<std::string> percent_decode(std::string_view in) {
  std::string out;
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in[i] != '%') {
      out.push_back(in[i]);
      continue;
    }
    if (i + 2 >= in.size()) return std::nullopt;
    const int hi = hex_value(in[i + 1]);
    const int lo = hex_value(in[i + 2]);
    if (hi < 0 || lo < 0) return std::nullopt;
    out.push_back(static_cast<char>(hi * 16 + lo));
    i += 2;
  }
  return out;
}

bool inside(const std::filesystem::path& root, const std::filesystem::path& p) {
  auto r = root.begin();
  auto q = p.begin();
  for (; r != root.end(); ++r, ++q)
    if (q == p.end() || *r != *q) return false;
  return true;
}

// What index.html loads from node_modules: its import map (three, its addons' OrbitControls,
// lil-gui, uplot), three.module.js's own import, and uPlot's stylesheet.
constexpr std::array<std::string_view, 6> kServedModuleFiles{
    "node_modules/three/build/three.module.js",
    "node_modules/three/build/three.core.js",
    "node_modules/three/examples/jsm/controls/OrbitControls.js",
    "node_modules/lil-gui/dist/lil-gui.esm.js",
    "node_modules/uplot/dist/uPlot.esm.js",
    "node_modules/uplot/dist/uPlot.min.css",
};

}  // namespace

StaticLookup resolve_static(const std::filesystem::path& root, std::string_view target) {
  namespace fs = std::filesystem;
  target = target.substr(0, target.find_first_of("?#"));
  if (target.empty() || target.front() != '/') return {.status = 400};
  const std::optional<std::string> decoded = percent_decode(target);
  if (!decoded) return {.status = 400};
  std::string path = *decoded;
  if (path.find('\0') != std::string::npos || path.find('\\') != std::string::npos)
    return {.status = 403};
  if (path.back() == '/') path += "index.html";

  // Every segment must be a plain name: no "..", ".", or empty segments ("//").
  fs::path relative;
  std::size_t start = 1;
  for (; start <= path.size();) {
    const std::size_t end = std::min(path.find('/', start), path.size());
    const std::string_view segment(path.data() + start, end - start);
    if (segment.empty() || segment.front() == '.') return {.status = 403};
    if (segment == "node_modules" && !relative.empty()) return {.status = 403};  // Only at the top.
    relative /= fs::path(std::string(segment));
    start = end + 1;
  }
  // Of web/node_modules only the files the page imports (its import map and their own
  // imports) are served; the rest (other builds of the same packages, build and test
  // tooling, playwright-core among it: 38 MB) never is, nor are dotfiles (.git, .env …).
  if (*relative.begin() == "node_modules" &&
      std::find(kServedModuleFiles.begin(), kServedModuleFiles.end(),
                std::string_view(path).substr(1)) == kServedModuleFiles.end())
    return {.status = 403};

  std::error_code ec;
  const fs::path resolved = fs::canonical(root / relative, ec);  // Follows symlinks.
  if (ec) return {.status = 404};
  if (!inside(root, resolved)) return {.status = 403};
  if (!fs::is_regular_file(resolved, ec)) return {.status = 404};
  return {200, resolved, resolved.lexically_relative(root)};
}

namespace {

unsigned status_of(int error) {
  return error == EXDEV || error == ELOOP || error == EACCES || error == EPERM ? 403u : 404u;
}

// Where openat2 is missing (Linux < 5.6, or filtered by seccomp): one component at a time,
// never following a symlink (the same rule as RESOLVE_NO_SYMLINKS).
int open_without_links(int root_fd, const std::filesystem::path& relative) {
  int dir = root_fd;
  int fd = -1;
  for (auto it = relative.begin(); it != relative.end();) {
    const std::filesystem::path& part = *it;
    const bool last = ++it == relative.end();
    const int flags = last ? O_RDONLY | O_NONBLOCK | O_NOCTTY : O_PATH | O_DIRECTORY;
    fd = ::openat(dir, part.c_str(), flags | O_NOFOLLOW | O_CLOEXEC);
    const int error = errno;
    if (dir != root_fd) ::close(dir);
    if (fd < 0) {
      errno = error;
      return -1;
    }
    dir = fd;
  }
  return fd;
}

}  // namespace

OpenedFile open_beneath(int root_fd, const std::filesystem::path& relative) {
  if (root_fd < 0 || relative.empty()) return {};
  open_how how{};
  how.flags = O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC;  // O_NONBLOCK: a FIFO can't hang us.
  how.resolve = RESOLVE_BENEATH | RESOLVE_NO_SYMLINKS;
  int fd = static_cast<int>(::syscall(SYS_openat2, root_fd, relative.c_str(), &how, sizeof how));
  if (fd < 0 && (errno == ENOSYS || errno == EPERM)) fd = open_without_links(root_fd, relative);
  if (fd < 0) return {-1, status_of(errno)};
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    return {};
  }
  return {fd, 200};
}

std::string_view mime_type(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".html" || ext == ".htm") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json" || ext == ".map") return "application/json";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  if (ext == ".jpg" || ext == ".jpeg") return "image/jpeg";
  if (ext == ".gif") return "image/gif";
  if (ext == ".ico") return "image/vnd.microsoft.icon";
  if (ext == ".wasm") return "application/wasm";
  if (ext == ".txt" || ext == ".md") return "text/plain; charset=utf-8";
  if (ext == ".woff2") return "font/woff2";
  if (ext == ".glb") return "model/gltf-binary";
  if (ext == ".gltf") return "model/gltf+json";
  return "application/octet-stream";
}

}  // namespace tumble::server
