#pragma once
/// Reporting of I/O failures (Beast examples' fail(ec, what)). Thread-safe.
#include <boost/beast/core/error.hpp>

namespace tumble::server {

/// True for the ways a connection normally ends: closed, aborted, reset, eof, timed out.
bool is_normal_end(boost::beast::error_code ec);

/// Writes "what: message" to stderr unless `ec` is a normal end.
void fail(boost::beast::error_code ec, const char* what);

}  // namespace tumble::server
