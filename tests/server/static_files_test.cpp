#include "static_files.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

namespace tumble::server {
namespace {

namespace fs = std::filesystem;

class StaticFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() / ("tumble_static_test_" + std::to_string(rd()));
    fs::create_directories(dir_ / "web" / "src");
    fs::create_directories(dir_ / "web" / "empty");
    std::ofstream(dir_ / "web" / "index.html") << "index";
    std::ofstream(dir_ / "web" / "src" / "main.mjs") << "js";
    std::ofstream(dir_ / "web" / "src" / "index.html") << "sub";
    std::ofstream(dir_ / "web" / "a b.css") << "css";
    std::ofstream(dir_ / "secret.txt") << "secret";
    fs::create_symlink(dir_ / "secret.txt", dir_ / "web" / "leak.txt");
    fs::create_symlink(dir_ / "web" / "src" / "main.mjs", dir_ / "web" / "alias.mjs");
    fs::create_directory_symlink(dir_, dir_ / "web" / "up");
    root_ = fs::canonical(dir_ / "web");
  }
  void TearDown() override { fs::remove_all(dir_); }

  StaticLookup at(std::string_view target) { return resolve_static(root_, target); }

  fs::path dir_, root_;
};

TEST_F(StaticFiles, ServesFilesAndIndex) {
  EXPECT_EQ(at("/").file, root_ / "index.html");
  EXPECT_EQ(at("/index.html?v=3").file, root_ / "index.html");
  EXPECT_EQ(at("/src/main.mjs").file, root_ / "src" / "main.mjs");
  EXPECT_EQ(at("/src/").file, root_ / "src" / "index.html");
  EXPECT_EQ(at("/a%20b.css").file, root_ / "a b.css");
  EXPECT_EQ(at("/alias.mjs").status, 200u);  // A symlink that stays inside is fine.
}

TEST_F(StaticFiles, RefusesTraversal) {
  for (const char* t : {"/../secret.txt", "/src/../../secret.txt", "/%2e%2e/secret.txt",
                        "/%2E%2E/secret.txt", "/src/%2e%2e/%2e%2e/secret.txt", "/..%2fsecret.txt",
                        "/.%2e/secret.txt", "//etc/passwd", "/src/./main.mjs", "/..\\secret.txt",
                        "/%5c..%5csecret.txt", "/index.html%00.css", "/leak.txt",
                        "/up/secret.txt"}) {
    const StaticLookup r = at(t);
    EXPECT_EQ(r.status, 403u) << t;
    EXPECT_TRUE(r.file.empty()) << t;
  }
  EXPECT_EQ(at("relative/index.html").status, 400u);
  EXPECT_EQ(at("/%zz").status, 400u);
  EXPECT_EQ(at("/%2").status, 400u);
}

TEST_F(StaticFiles, NoDirectoryListingAndMissingFiles) {
  EXPECT_EQ(at("/src").status, 404u);
  EXPECT_EQ(at("/empty/").status, 404u);
  EXPECT_EQ(at("/empty").status, 404u);
  EXPECT_EQ(at("/nope.js").status, 404u);
}

TEST(MimeTypes, CommonExtensions) {
  EXPECT_EQ(mime_type("a/index.html"), "text/html; charset=utf-8");
  EXPECT_EQ(mime_type("m.mjs"), "text/javascript; charset=utf-8");
  EXPECT_EQ(mime_type("m.JS"), "text/javascript; charset=utf-8");
  EXPECT_EQ(mime_type("s.css"), "text/css; charset=utf-8");
  EXPECT_EQ(mime_type("d.json"), "application/json");
  EXPECT_EQ(mime_type("i.svg"), "image/svg+xml");
  EXPECT_EQ(mime_type("p.png"), "image/png");
  EXPECT_EQ(mime_type("w.wasm"), "application/wasm");
  EXPECT_EQ(mime_type("noext"), "application/octet-stream");
}

}  // namespace
}  // namespace tumble::server
