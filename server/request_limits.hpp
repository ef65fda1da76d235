#pragma once
/// Limits on one HTTP request and the framing checks made on its header before any of its
/// body is read (RFC 9112). Pure functions; thread-safe.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <boost/beast/http.hpp>

namespace tumble::server {

/// Largest request body, bytes (larger: 413).
inline constexpr std::uint64_t kBodyLimit = 1 << 20;
/// Largest request header block, bytes (larger: 431).
inline constexpr std::uint32_t kHeaderLimit = 16 * 1024;
/// Largest number of bytes a connection's read buffer may hold, bytes. Unparsed input
/// (a header, a chunk header line with its extensions, a trailer block) must fit in it;
/// beyond: 400 and close. Twice the header limit, so that a header block at its limit fits.
inline constexpr std::size_t kReadBufferLimit = 2 * kHeaderLimit;
/// Longest chunk extension accepted on one chunk, bytes (longer: 400 and close).
inline constexpr std::size_t kChunkExtensionLimit = 256;
/// Deepest JSON nesting accepted in a request body (deeper: 400 before parsing).
inline constexpr std::size_t kJsonDepthLimit = 32;

/// A request refused on its header: the status, the message and the field named.
struct FramingRefusal {
  unsigned status;       ///< 400, 417 or 501.
  std::string message;   ///< For the JSON error.
  std::string field;     ///< The header at fault ("Transfer-Encoding", "Host" …).
};

/// The request parser of HttpSession and of the fuzz targets.
using RequestParser = boost::beast::http::request_parser<boost::beast::http::string_body>;

/// Sets the body and header limits and bounds chunk extensions (Beast 1.81 bounds neither the
/// chunk header line nor the trailer: the read buffer's limit and this callback do).
void limit_parser(RequestParser& parser);

/// Checks a parsed request header: Transfer-Encoding exactly "chunked" (another coding last:
/// 400, chunked after another coding: 501; RFC 9112 §6.1, §6.3), not both Content-Length and
/// Transfer-Encoding (400, §6.3), one Host on HTTP/1.1 (400, §3.2), Expect only
/// "100-continue" (417, RFC 9110 §10.1.1). Every refusal closes the connection.
std::optional<FramingRefusal> check_framing(
    const boost::beast::http::request_header<>& header);

/// The fields of a request's header, by identity (their addresses, sorted), taken when the
/// header is read: Beast adds a chunked body's trailer fields to the same list, and places a
/// repeated name beside its first use, so only identity tells a trailer's field apart.
using HeaderFields = std::vector<const void*>;

/// The header fields of `header` as they are now. Linear in their count, which the header
/// limit bounds.
HeaderFields header_fields(const boost::beast::http::request_header<>& header);

/// Refuses a request that gained trailer fields after `header` was taken (400, naming the
/// first): the handler would read them as if sent in the header, so a trailer could add
/// Authorization or Origin, which RFC 9110 §6.5.1 forbids in trailers, or repeat Host.
std::optional<FramingRefusal> check_trailer(const boost::beast::http::request_header<>& request,
                                            const HeaderFields& header);

/// True when the client waits for "100 Continue" before sending its body.
bool expects_continue(const boost::beast::http::request_header<>& header);

/// True when `body` nests arrays and objects deeper than `limit` (strings are skipped). A
/// linear scan, so that a body of a million '[' costs microseconds, not a recursive parse.
bool json_too_deep(std::string_view body, std::size_t limit = kJsonDepthLimit);

/// `text` cut to at most `limit` bytes (on a UTF-8 boundary) with "…" appended when cut:
/// for error messages that quote what the client sent.
std::string quoted_prefix(std::string_view text, std::size_t limit = 64);

}  // namespace tumble::server
