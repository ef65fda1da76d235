#pragma once
/// A real tumble-server in-process on 127.0.0.1, port 0, with a temporary web root holding a
/// few files, a secret file beside it and symlinks pointing inside and outside.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <thread>

#include "server.hpp"
#include "test_client.hpp"
#include "tumble/scene_io.hpp"

namespace tumble::server::test {

/// Writes `text` to `path`.
inline void write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

/// Base fixture: a server per test (started in SetUp, stopped in TearDown).
class ServerTest : public ::testing::Test {
 protected:
  /// Options for this test; override to change them before the server starts.
  virtual void configure(ServerOptions&) {}
  /// The scene the server starts with.
  virtual Scene initial_scene() { return load_scene("seed"); }
  /// Called after the server is built and before it starts (e.g. to set test seams).
  virtual void before_start(Server&) {}

  void SetUp() override {
    namespace fs = std::filesystem;
    std::random_device rd;
    dir_ = fs::temp_directory_path() / ("tumble_server_test_" + std::to_string(rd()));
    fs::create_directories(dir_ / "web" / "src");
    fs::create_directories(dir_ / "web" / "empty");
    write_file(dir_ / "web" / "index.html", "<!doctype html><title>tumble</title>");
    write_file(dir_ / "web" / "src" / "main.mjs", "export const x = 1;");
    write_file(dir_ / "web" / "src" / "viewer.js", "export const y = 2;");
    write_file(dir_ / "web" / "style.css", "body{}");
    write_file(dir_ / "web" / "data.json", "{}");
    write_file(dir_ / "secret.txt", "TOP-SECRET");
    fs::create_directories(dir_ / "web" / "node_modules" / "pkg");
    write_file(dir_ / "web" / "node_modules" / "pkg" / "index.js", "export const npm = 1;");
    write_file(dir_ / "web" / ".env", "TOKEN=dotfile");
    fs::create_symlink(dir_ / "secret.txt", dir_ / "web" / "leak.txt");
    fs::create_symlink(dir_ / "web" / "style.css", dir_ / "web" / "alias.css");
    fs::create_directory_symlink(dir_, dir_ / "web" / "up");

    ServerOptions o;
    o.port = 0;
    o.bind = "127.0.0.1";
    o.web_root = dir_ / "web";
    o.threads = 2;
    configure(o);
    server_ = std::make_unique<Server>(o, initial_scene());
    before_start(*server_);
    server_->start();
    port_ = server_->port();
  }

  void TearDown() override {
    server_.reset();
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }

  /// GET /api/state as JSON.
  nlohmann::json state() { return http_get(port_, "/api/state").json(); }

  std::filesystem::path dir_;
  std::unique_ptr<Server> server_;
  std::uint16_t port_ = 0;
};

}  // namespace tumble::server::test
