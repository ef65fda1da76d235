// HTTP limits and static files against a real server.
#include <gtest/gtest.h>

#include "server_fixture.hpp"

namespace tumble::server::test {
namespace {

namespace http = boost::beast::http;

class HttpSessionTest : public ServerTest {};

TEST_F(HttpSessionTest, ServesIndexAndFilesWithMimeTypes) {
  HttpReply r = http_get(port_, "/");
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.body, "<!doctype html><title>tumble</title>");
  EXPECT_EQ(r.headers[http::field::content_type], "text/html; charset=utf-8");
  EXPECT_EQ(r.headers["X-Content-Type-Options"], "nosniff");
  r = http_get(port_, "/src/main.mjs");
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.headers[http::field::content_type], "text/javascript; charset=utf-8");
  EXPECT_EQ(http_get(port_, "/src/viewer.js").headers[http::field::content_type],
            "text/javascript; charset=utf-8");
  EXPECT_EQ(http_get(port_, "/style.css").headers[http::field::content_type],
            "text/css; charset=utf-8");
  EXPECT_EQ(http_get(port_, "/data.json").headers[http::field::content_type], "application/json");
  r = http_request(port_, http::verb::head, "/index.html");
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.headers[http::field::content_length], "36");
}

// A current copy is revalidated: 304, no body, the validators and the cross-origin isolation
// headers kept, and no Content-Type (the cached copy's stands; RFC 9110 §15.4.5). A tag that
// does not match gets the file again.
TEST_F(HttpSessionTest, ACurrentCopyGets304WithoutBody) {
  const HttpReply first = http_get(port_, "/src/main.mjs");
  ASSERT_EQ(first.status, 200u);
  const std::string etag(first.headers[http::field::etag]);
  ASSERT_FALSE(etag.empty());
  const auto get_if_none_match = [&](const std::string& tag) {
    return raw_request(port_, "GET /src/main.mjs HTTP/1.1\r\nHost: 127.0.0.1\r\nIf-None-Match: " +
                                  tag + "\r\n\r\n");
  };
  HttpReply r = get_if_none_match(etag);
  EXPECT_EQ(r.status, 304u);
  EXPECT_EQ(r.body, "");
  EXPECT_EQ(r.headers[http::field::etag], etag);
  EXPECT_EQ(r.headers[http::field::cache_control], "no-cache");
  EXPECT_EQ(r.headers["Cross-Origin-Embedder-Policy"], "require-corp");
  EXPECT_EQ(r.headers["Cross-Origin-Opener-Policy"], "same-origin");
  EXPECT_EQ(r.headers.count(http::field::content_type), 0u);
  r = get_if_none_match("\"0-0-0\"");
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.body, first.body);
  EXPECT_EQ(r.headers[http::field::content_type], "text/javascript; charset=utf-8");
}

TEST_F(HttpSessionTest, RefusesPathTraversal) {
  for (const std::string target :
       {"/../secret.txt", "/%2e%2e/secret.txt", "/%2E%2e/%2e%2E/etc/passwd", "/..%2Fsecret.txt",
        "/leak.txt", "/up/secret.txt", "/src/../../secret.txt", "//etc/passwd",
        "/..\\secret.txt"}) {
    const HttpReply r = raw_request(
        port_, "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
    EXPECT_TRUE(r.status == 403u || r.status == 400u) << target << " → " << r.status;
    EXPECT_EQ(r.body.find("TOP-SECRET"), std::string::npos) << target;
  }
  EXPECT_EQ(http_get(port_, "/alias.css").status, 200u);  // Symlink inside the root.
}

TEST_F(HttpSessionTest, NoDirectoryListing) {
  EXPECT_EQ(http_get(port_, "/src").status, 404u);
  EXPECT_EQ(http_get(port_, "/empty/").status, 404u);
  EXPECT_EQ(http_get(port_, "/missing.js").status, 404u);
}

TEST_F(HttpSessionTest, StaticFilesAreReadOnly) {
  const HttpReply r = http_post(port_, "/index.html", "x");
  EXPECT_EQ(r.status, 405u);
  EXPECT_EQ(r.headers[http::field::allow], "GET, HEAD");
}

TEST_F(HttpSessionTest, BodyOverOneMebibyteIs413) {
  // Announced length over the limit: refused before the body is read.
  HttpReply r = raw_request(port_,
                            "POST /api/reset HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                            "Content-Type: application/json\r\nContent-Length: 2000000\r\n\r\n");
  EXPECT_EQ(r.status, 413u) << r.error.message();
  // A real body over the limit.
  r = http_post(port_, "/api/reset", std::string((1 << 20) + 10, ' '));
  EXPECT_EQ(r.status, 413u) << r.error.message();
  // Just under the limit: read and judged on its content.
  r = http_post(port_, "/api/reset", std::string((1 << 20) - 10, ' '));
  EXPECT_EQ(r.status, 200u) << r.body;
}

TEST_F(HttpSessionTest, HugeHeadersAre431) {
  const HttpReply r = raw_request(port_, "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: " +
                                             std::string(64 * 1024, 'a') + "\r\n\r\n");
  EXPECT_EQ(r.status, 431u) << r.error.message();
}

TEST_F(HttpSessionTest, MalformedRequestIs400) {
  const HttpReply r = raw_request(port_, "GARBAGE\r\n\r\n");
  EXPECT_EQ(r.status, 400u) << r.error.message();
}

TEST_F(HttpSessionTest, KeepAliveServesSeveralRequests) {
  const HttpReply r = raw_request(port_,
                                  "GET /api/health HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.headers[http::field::connection], "");  // keep-alive is HTTP/1.1's default
}

TEST_F(HttpSessionTest, WebSocketPathOnlyByUpgrade) {
  EXPECT_EQ(http_get(port_, "/ws").status, 426u);
  EXPECT_THROW(
      {
        auto c = std::make_unique<WsClient>(port_, "http://evil.example");
      },
      boost::system::system_error);
}

}  // namespace
}  // namespace tumble::server::test
