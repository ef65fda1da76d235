#include "request_limits.hpp"

#include <algorithm>
#include <cctype>

namespace tumble::server {

namespace http = boost::beast::http;

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool iequals(std::string_view a, std::string_view b) {
  return a.size() == b.size() &&
         std::equal(a.begin(), a.end(), b.begin(), [](unsigned char x, unsigned char y) {
           return std::tolower(x) == std::tolower(y);
         });
}

std::size_t count(const http::request_header<>& h, http::field f) {
  const auto range = h.equal_range(f);
  return static_cast<std::size_t>(std::distance(range.first, range.second));
}

}  // namespace

void limit_parser(RequestParser& parser) {
  parser.body_limit(kBodyLimit);
  parser.header_limit(kHeaderLimit);
  // Beast keeps a reference to the callback: one for the whole program.
  static auto bound_extensions = [](std::uint64_t, boost::beast::string_view extensions,
                                    boost::beast::error_code& ec) {
    if (extensions.size() > kChunkExtensionLimit) ec = http::error::bad_chunk_extension;
  };
  parser.on_chunk_header(bound_extensions);
}

// Request smuggling (RFC 9112 §6.3, §11.2): when a front proxy and this server disagree on
// where a body ends, the rest of the body is read as a second request. So every framing this
// server does not read exactly as written is refused, and the connection closed.
std::optional<FramingRefusal> check_framing(const http::request_header<>& h) {
  const std::size_t te = count(h, http::field::transfer_encoding);
  if (te > 1)
    return FramingRefusal{400, "more than one Transfer-Encoding header", "Transfer-Encoding"};
  if (te == 1) {
    const std::string_view value = trim(h[http::field::transfer_encoding]);
    if (count(h, http::field::content_length) > 0)
      return FramingRefusal{400, "both Content-Length and Transfer-Encoding",
                            "Transfer-Encoding"};
    if (!iequals(value, "chunked")) {
      const std::size_t comma = value.rfind(',');
      const std::string_view last =
          trim(comma == std::string_view::npos ? value : value.substr(comma + 1));
      if (iequals(last, "chunked"))
        return FramingRefusal{501, "only the chunked transfer coding is implemented",
                              "Transfer-Encoding"};
      return FramingRefusal{400, "Transfer-Encoding must be exactly 'chunked'",
                            "Transfer-Encoding"};
    }
  }
  if (count(h, http::field::content_length) > 1)
    return FramingRefusal{400, "more than one Content-Length header", "Content-Length"};
  const std::size_t hosts = count(h, http::field::host);
  if (hosts > 1) return FramingRefusal{400, "more than one Host header", "Host"};
  if (h.version() >= 11 && hosts == 0)
    return FramingRefusal{400, "an HTTP/1.1 request needs a Host header", "Host"};
  const std::size_t expect = count(h, http::field::expect);
  if (expect > 1 || (expect == 1 && !iequals(trim(h[http::field::expect]), "100-continue")))
    return FramingRefusal{417, "only 'Expect: 100-continue' is understood", "Expect"};
  return std::nullopt;
}

HeaderFields header_fields(const http::request_header<>& h) {
  HeaderFields fields;
  for (const auto& f : h) fields.push_back(&f);
  std::sort(fields.begin(), fields.end());
  return fields;
}

std::optional<FramingRefusal> check_trailer(const http::request_header<>& request,
                                            const HeaderFields& header) {
  for (const auto& f : request) {
    if (std::binary_search(header.begin(), header.end(), static_cast<const void*>(&f))) continue;
    return FramingRefusal{400, "trailer fields are not accepted", quoted_prefix(f.name_string())};
  }
  return std::nullopt;
}

bool expects_continue(const http::request_header<>& h) {
  return h.version() >= 11 && iequals(trim(h[http::field::expect]), "100-continue");
}

bool json_too_deep(std::string_view body, std::size_t limit) {
  std::size_t depth = 0;
  bool in_string = false;
  bool escaped = false;
  for (const char c : body) {
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > limit) return true;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return false;
}

std::string quoted_prefix(std::string_view text, std::size_t limit) {
  if (text.size() <= limit) return std::string(text);
  std::size_t cut = limit;
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xc0) == 0x80) --cut;
  return std::string(text.substr(0, cut)) + "…";
}

}  // namespace tumble::server
