// tumble-sim, the headless CLI: the overlap bound from the command line, and a bad value
// refused with the field named and exit code 2.
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "child_process.hpp"

namespace tumble::server::test {
namespace {

/// tumble-sim with `args`: (exit code, output).
std::pair<int, std::string> run_sim(std::vector<std::string> args) {
  args.insert(args.begin(), TUMBLE_SIM_BINARY);
  ChildProcess sim(args);
  std::string out = sim.rest();
  return {sim.wait(), out};
}

TEST(SimCli, MaxOverlapBoundsTheStepsAndCountsItsPasses) {
  const auto [code, out] =
      run_sim({"pile", "--duration", "0.75", "--threads", "1", "--max-overlap", "0.01"});
  ASSERT_EQ(code, 0) << out;
  const nlohmann::json line = nlohmann::json::parse(out);
  EXPECT_EQ(line["max_overlap"], 0.01);
  EXPECT_EQ(line["steps"], 45);
  EXPECT_GT(line["passes"].get<int>(), 45);  // the landing's steps were taken in halves
  EXPECT_EQ(line["steps_alone"], 0);  // one thread has no worker to be held up by
  const auto [plain_code, plain_out] = run_sim({"pile", "--duration", "0.75", "--threads", "1"});
  ASSERT_EQ(plain_code, 0) << plain_out;
  EXPECT_EQ(nlohmann::json::parse(plain_out)["passes"], 45);
}

TEST(SimCli, ABoundUnderAMillimetreIsRefusedByName) {
  const auto [code, out] = run_sim({"bounce", "--max-overlap", "0.0001"});
  EXPECT_EQ(code, 2);
  EXPECT_NE(out.find("max_overlap"), std::string::npos) << out;
  EXPECT_EQ(run_sim({"bounce", "--max-overlap", "x"}).first, 2);
}

}  // namespace
}  // namespace tumble::server::test
