#include "options.hpp"
#include "tumble/scene_io.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

namespace tumble::server {
namespace {

ParsedOptions parse(std::vector<const char*> args) {
  args.insert(args.begin(), "tumble-server");
  return parse_options(static_cast<int>(args.size()), args.data());
}

// Sets an environment variable for the lifetime of the object.
struct EnvVar {
  EnvVar(const char* name, const char* value) : name(name) { setenv(name, value, 1); }
  ~EnvVar() { unsetenv(name); }
  const char* name;
};

TEST(Options, Defaults) {
  const ParsedOptions p = parse({});
  ASSERT_TRUE(p.options) << p.message;
  EXPECT_EQ(p.options->scene, "seed");
  EXPECT_EQ(p.options->port, 8080);
  EXPECT_EQ(p.options->bind, "127.0.0.1");
  EXPECT_EQ(p.options->render_ms, 20);
  EXPECT_EQ(p.options->threads, 2);
  EXPECT_EQ(p.options->max_viewers, 64);
  EXPECT_EQ(p.options->token, "");
  EXPECT_EQ(p.options->web_root, default_web_root());
  EXPECT_FALSE(p.options->token_reads);
  EXPECT_EQ(p.options->max_connections, 512);
  EXPECT_EQ(p.options->step_budget_ms, 5000);
  EXPECT_EQ(p.options->viewer_timeout_ms, 15000);
  EXPECT_EQ(p.options->read_budget, 20000);
  EXPECT_EQ(p.options->sim_threads, 0);
  EXPECT_EQ(p.options->step_threads, 1);
  EXPECT_EQ(p.options->max_worlds, 64);
}

// --sim-threads: the pool all worlds share, 0 (the cores)..256; --step-threads: the threads
// of each step, 1..256; both also from the environment.
TEST(Options, SimThreads) {
  const ParsedOptions p = parse({"--sim-threads", "3", "--step-threads", "2"});
  ASSERT_TRUE(p.options) << p.message;
  EXPECT_EQ(p.options->sim_threads, 3);
  EXPECT_EQ(p.options->step_threads, 2);
  for (const char* bad : {"-1", "257", "two"}) {
    const ParsedOptions r = parse({"--sim-threads", bad});
    EXPECT_FALSE(r.options) << bad;
    EXPECT_EQ(r.exit_code, 2) << bad;
    EXPECT_NE(r.message.find("sim-threads"), std::string::npos) << r.message;
  }
  for (const char* bad : {"0", "257"}) {
    const ParsedOptions r = parse({"--step-threads", bad});
    EXPECT_FALSE(r.options) << bad;
    EXPECT_NE(r.message.find("step-threads"), std::string::npos) << r.message;
  }
  EnvVar env("TUMBLE_SIM_THREADS", "2");
  const ParsedOptions e = parse({});
  ASSERT_TRUE(e.options) << e.message;
  EXPECT_EQ(e.options->sim_threads, 2);
}

// Every bundled scene fits the default --max-bodies: the viewer's scene menu offers them all.
TEST(Options, EveryBundledSceneFitsTheDefaultBodyLimit) {
  const ParsedOptions p = parse({});
  ASSERT_TRUE(p.options);
  for (const std::string& name : bundled_scene_names())
    EXPECT_LE(load_scene(name).bodies.size(), static_cast<std::size_t>(p.options->max_bodies))
        << name;
}

// The worlds' limits: each refused outside its range with exit code 2 and its name.
TEST(Options, WorldLimits) {
  const ParsedOptions p = parse({"--max-worlds", "3", "--max-bodies", "10", "--idle-s", "0.5",
                                 "--idle-remove-s", "2"});
  ASSERT_TRUE(p.options) << p.message;
  EXPECT_EQ(p.options->max_worlds, 3);
  EXPECT_EQ(p.options->max_bodies, 10);
  EXPECT_EQ(p.options->idle_s, 0.5);
  EXPECT_EQ(p.options->idle_remove_s, 2.0);
  EXPECT_EQ(p.options->io_nice, 5) << "the default";
  const std::vector<std::vector<std::string>> bad = {
      {"--max-worlds", "0"}, {"--max-bodies", "0"}, {"--idle-s", "0"}, {"--io-nice", "20"},
      {"--idle-s", "10", "--idle-remove-s", "5"}};
  for (const auto& args : bad) {
    std::vector<const char*> argv;
    for (const auto& a : args) argv.push_back(a.c_str());
    const ParsedOptions r = parse(argv);
    EXPECT_FALSE(r.options) << args[0];
    EXPECT_EQ(r.exit_code, 2) << args[0];
    EXPECT_NE(r.message.find(args.back() == "5" ? "idle-remove-s" : args[0].substr(2)),
              std::string::npos) << r.message;
  }
}

TEST(Options, HardeningLimits) {
  const ParsedOptions p =
      parse({"--token", "t", "--token-reads", "--max-connections", "100", "--step-budget-ms",
             "250", "--viewer-timeout-ms", "2000", "--read-budget", "0"});
  ASSERT_TRUE(p.options) << p.message;
  EXPECT_TRUE(p.options->token_reads);
  EXPECT_EQ(p.options->max_connections, 100);
  EXPECT_EQ(p.options->step_budget_ms, 250);
  EXPECT_EQ(p.options->viewer_timeout_ms, 2000);
  EXPECT_EQ(p.options->read_budget, 0);
  for (std::vector<const char*> bad :
       {std::vector<const char*>{"--token-reads"}, {"--max-connections", "0"},
        {"--step-budget-ms", "5"}, {"--viewer-timeout-ms", "10"}, {"--read-budget", "-1"}}) {
    const ParsedOptions r = parse(bad);
    EXPECT_FALSE(r.options) << bad[0];
    EXPECT_EQ(r.exit_code, 2) << bad[0];
  }
}

TEST(Options, CommandLine) {
  const ParsedOptions p = parse({"--scene", "bounce", "--port", "9000", "--bind", "0.0.0.0",
                                 "--render-ms", "10", "--threads", "3", "--token", "t0k",
                                 "--max-viewers", "5", "--allowed-origin", "http://x:1",
                                 "--web-root", "/tmp"});
  ASSERT_TRUE(p.options) << p.message;
  EXPECT_EQ(p.options->scene, "bounce");
  EXPECT_EQ(p.options->port, 9000);
  EXPECT_EQ(p.options->bind, "0.0.0.0");
  EXPECT_EQ(p.options->render_ms, 10);
  EXPECT_EQ(p.options->threads, 3);
  EXPECT_EQ(p.options->token, "t0k");
  EXPECT_EQ(p.options->max_viewers, 5);
  EXPECT_EQ(p.options->allowed_origin, "http://x:1");
  EXPECT_EQ(p.options->web_root, "/tmp");
}

TEST(Options, EnvironmentAndCommandLineWins) {
  EnvVar port("TUMBLE_PORT", "9100");
  EnvVar scene("TUMBLE_SCENE", "many");
  EnvVar render("TUMBLE_RENDER_MS", "40");
  EnvVar viewers("TUMBLE_MAX_VIEWERS", "7");
  EnvVar unrelated("TUMBLE_SCENES_DIR", "/nowhere");  // The engine's, not an option.
  ParsedOptions p = parse({});
  ASSERT_TRUE(p.options) << p.message;
  EXPECT_EQ(p.options->port, 9100);
  EXPECT_EQ(p.options->scene, "many");
  EXPECT_EQ(p.options->render_ms, 40);
  EXPECT_EQ(p.options->max_viewers, 7);
  p = parse({"--port", "9200"});
  ASSERT_TRUE(p.options) << p.message;
  EXPECT_EQ(p.options->port, 9200);
  EXPECT_EQ(p.options->scene, "many");
}

TEST(Options, BadInputExitsWithTwo) {
  for (const auto& args : std::vector<std::vector<const char*>>{
           {"--port", "70000"}, {"--port", "abc"}, {"--bogus"}, {"--render-ms", "0"},
           {"--threads", "0"}, {"--bind", "not-an-address"}, {"--max-viewers", "-1"},
           {"--port"}}) {
    const ParsedOptions p = parse(args);
    EXPECT_FALSE(p.options) << args[0];
    EXPECT_EQ(p.exit_code, 2) << args[0];
    EXPECT_NE(p.message.find("Usage"), std::string::npos);
  }
  EnvVar port("TUMBLE_PORT", "x");
  EXPECT_EQ(parse({}).exit_code, 2);
}

TEST(Options, HelpExitsWithZero) {
  const ParsedOptions p = parse({"--help"});
  EXPECT_FALSE(p.options);
  EXPECT_EQ(p.exit_code, 0);
  EXPECT_NE(p.message.find("--render-ms"), std::string::npos);
}

}  // namespace
}  // namespace tumble::server
