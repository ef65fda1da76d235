#pragma once
/// Validators and compressed copies of static files: an ETag per file version (inode, size,
/// modification time) and, for text files, a gzip copy made once per version with zlib and
/// kept in memory. Thread-safe.
#include <sys/stat.h>

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

namespace tumble::server {

/// The strong ETag (quoted) of a file version described by `st`.
std::string file_etag(const struct stat& st);

/// True when an If-None-Match header value lists `etag` (or is "*"): the client's copy is
/// current. Weak ("W/") entries compare by their opaque part, as RFC 9110 §13.1.2 allows.
bool etag_matches(std::string_view if_none_match, std::string_view etag);

/// True when an Accept-Encoding header value accepts gzip (a q=0 refuses it).
bool accepts_gzip(std::string_view accept_encoding);

/// True for the content types worth compressing (text, JavaScript, JSON, SVG).
bool compressible(std::string_view content_type);

/// gzip copies of static files by path and version.
class StaticCache {
 public:
  /// Files larger than this are sent as they are, bytes.
  static constexpr std::size_t kMaxFile = 8u << 20;

  /// The gzip copy of the file open as `fd` (its stat `st`, its path `relative` under the
  /// root), made on the first request for this version; null when it is not smaller or the
  /// file cannot be read.
  std::shared_ptr<const std::string> gzip(const std::string& relative, int fd,
                                          const struct stat& st);

 private:
  std::mutex mutex_;
  std::map<std::string, std::pair<std::string, std::shared_ptr<const std::string>>> entries_;
};

}  // namespace tumble::server
