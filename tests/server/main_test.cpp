// The tumble-server binary as a process: exit codes, the URL line, SIGTERM.
#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "test_client.hpp"

namespace tumble::server::test {
namespace {

using namespace std::chrono_literals;

// A child tumble-server with its stdout and stderr on a pipe.
struct Child : ChildProcess {
  explicit Child(std::vector<std::string> args) : ChildProcess(with_binary(std::move(args))) {}
  static std::vector<std::string> with_binary(std::vector<std::string> args) {
    args.insert(args.begin(), TUMBLE_SERVER_BINARY);
    return args;
  }
};

std::uint16_t port_from(const std::string& url_line) {
  const auto colon = url_line.rfind(':');
  return static_cast<std::uint16_t>(std::stoi(url_line.substr(colon + 1)));
}

TEST(Main, PrintsTheUrlAndStopsCleanlyOnSigterm) {
  Child server({"--port", "0", "--scene", "bounce"});
  const std::string url = server.line();
  ASSERT_EQ(url.rfind("Tumble viewer: http://127.0.0.1:", 0), 0u) << url;
  const std::uint16_t port = port_from(url);
  EXPECT_EQ(http_get(port, "/api/health").status, 200u);
  WsClient viewer(port);
  ASSERT_TRUE(viewer.read());
  const auto t0 = std::chrono::steady_clock::now();
  server.signal(SIGTERM);
  bool closed = false;
  for (int i = 0; i < 200 && !closed; ++i) closed = !viewer.read(1s);
  EXPECT_EQ(viewer.last_error(), boost::beast::websocket::error::closed);
  EXPECT_EQ(server.wait(), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
}

TEST(Main, SigintAlsoExitsWithZero) {
  Child server({"--port", "0"});
  ASSERT_FALSE(server.line().empty());
  server.signal(SIGINT);
  EXPECT_EQ(server.wait(), 0);
}

TEST(Main, PortInUseExitsWithOne) {
  Child first({"--port", "0"});
  const std::uint16_t port = port_from(first.line());
  Child second({"--port", std::to_string(port)});
  const std::string message = second.rest();
  EXPECT_EQ(second.wait(), 1);
  EXPECT_NE(message.find("in use"), std::string::npos) << message;
}

TEST(Main, BadCommandLineExitsWithTwo) {
  Child bad({"--port", "nope"});
  EXPECT_NE(bad.rest().find("Usage"), std::string::npos);
  EXPECT_EQ(bad.wait(), 2);
  Child unknown({"--scene", "no-such-scene"});
  EXPECT_NE(unknown.rest().find("no-such-scene"), std::string::npos);
  EXPECT_EQ(unknown.wait(), 2);
}

}  // namespace
}  // namespace tumble::server::test
