// The tumble-server binary as a process: exit codes, the URL line, SIGTERM.
#include <gtest/gtest.h>

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "test_client.hpp"

extern char** environ;

namespace tumble::server::test {
namespace {

using namespace std::chrono_literals;

// A child tumble-server with its stdout and stderr on a pipe.
struct Child {
  pid_t pid = -1;
  FILE* out = nullptr;

  explicit Child(std::vector<std::string> args) {
    args.insert(args.begin(), TUMBLE_SERVER_BINARY);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    int fds[2];
    if (pipe(fds) != 0) return;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
    posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    close(fds[1]);
    out = fdopen(fds[0], "r");
  }
  ~Child() {
    if (pid > 0 && !exited) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    if (out) fclose(out);
  }
  std::string line() {
    char buf[4096];
    return out && fgets(buf, sizeof buf, out) ? std::string(buf) : std::string();
  }
  std::string rest() {
    std::string all;
    for (std::string l = line(); !l.empty(); l = line()) all += l;
    return all;
  }
  int wait() {
    int status = 0;
    waitpid(pid, &status, 0);
    exited = true;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  bool exited = false;
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
  kill(server.pid, SIGTERM);
  bool closed = false;
  for (int i = 0; i < 200 && !closed; ++i) closed = !viewer.read(1s);
  EXPECT_EQ(viewer.last_error(), boost::beast::websocket::error::closed);
  EXPECT_EQ(server.wait(), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
}

TEST(Main, SigintAlsoExitsWithZero) {
  Child server({"--port", "0"});
  ASSERT_FALSE(server.line().empty());
  kill(server.pid, SIGINT);
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
