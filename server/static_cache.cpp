#include "static_cache.hpp"

#include <unistd.h>
#include <zlib.h>

#include <cstdio>

namespace tumble::server {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool read_all(int fd, std::size_t size, std::string& out) {
  out.resize(size);
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::pread(fd, out.data() + done, size - done, static_cast<off_t>(done));
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

// gzip (RFC 1952) at level 9: made once per file version, so the slowest level is cheap.
std::shared_ptr<const std::string> gzip_of(const std::string& data) {
  z_stream z{};
  if (deflateInit2(&z, 9, Z_DEFLATED, 15 + 16, 9, Z_DEFAULT_STRATEGY) != Z_OK) return nullptr;
  std::string out(deflateBound(&z, data.size()) + 32, '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(data.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&z, Z_FINISH);
  out.resize(z.total_out);
  deflateEnd(&z);
  if (rc != Z_STREAM_END || out.size() >= data.size()) return nullptr;
  return std::make_shared<const std::string>(std::move(out));
}

}  // namespace

std::string file_etag(const struct stat& st) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "\"%llx-%llx-%llx\"", static_cast<unsigned long long>(st.st_ino),
                static_cast<unsigned long long>(st.st_size),
                static_cast<unsigned long long>(st.st_mtim.tv_sec) * 1000000000ull +
                    static_cast<unsigned long long>(st.st_mtim.tv_nsec));
  return buf;
}

bool etag_matches(std::string_view if_none_match, std::string_view etag) {
  while (!if_none_match.empty()) {
    const std::size_t comma = if_none_match.find(',');
    std::string_view item = trim(if_none_match.substr(0, comma));
    if (item == "*") return true;
    if (item.starts_with("W/")) item.remove_prefix(2);
    if (item == etag) return true;
    if (comma == std::string_view::npos) break;
    if_none_match.remove_prefix(comma + 1);
  }
  return false;
}

bool accepts_gzip(std::string_view accept_encoding) {
  while (!accept_encoding.empty()) {
    const std::size_t comma = accept_encoding.find(',');
    const std::string_view item = trim(accept_encoding.substr(0, comma));
    const std::size_t semi = item.find(';');
    if (trim(item.substr(0, semi)) == "gzip") {
      if (semi == std::string_view::npos) return true;
      std::string_view q = trim(item.substr(semi + 1));
      if (!q.starts_with("q=")) return true;
      q.remove_prefix(2);
      return q.find_first_not_of("0.") != std::string_view::npos;  // q=0, 0.0, 0.000: refused
    }
    if (comma == std::string_view::npos) break;
    accept_encoding.remove_prefix(comma + 1);
  }
  return false;
}

bool compressible(std::string_view type) {
  return type.starts_with("text/") || type.starts_with("application/json") ||
         type.starts_with("image/svg+xml");
}

std::shared_ptr<const std::string> StaticCache::gzip(const std::string& relative, int fd,
                                                     const struct stat& st) {
  const std::string version = file_etag(st);
  {
    std::lock_guard lock(mutex_);
    const auto it = entries_.find(relative);
    if (it != entries_.end() && it->second.first == version) return it->second.second;
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  std::string data;
  if (size > kMaxFile || !read_all(fd, size, data)) return nullptr;
  std::shared_ptr<const std::string> packed = gzip_of(data);
  std::lock_guard lock(mutex_);
  entries_[relative] = {version, packed};
  return packed;
}

}  // namespace tumble::server
