// `bench`, black box: bench --what node recommends the fastest record row.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::LinesWith;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;

TEST(RoughEdges, BenchNodeRecommendsTheFastestRecordRow) {
  TempDir tmp;
  const CommandResult r = RunFetchscope(
      "bench --what node --backends egl --seconds 0.4 --width 48 --height 48 --json-out " +
      (tmp.path() / "b.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json node = nlohmann::json::parse(ReadFile(tmp.path() / "b.json"))["node"];
  ASSERT_TRUE(node.contains("recommendation")) << node.dump(1);
  const nlohmann::json& rec = node["recommendation"];
  // the row with the most record frames/s
  const nlohmann::json* best = nullptr;
  for (const auto& row : node["record"]) {
    if (!row.contains("frames_per_s")) continue;
    if (!best || row["frames_per_s"].get<double>() > (*best)["frames_per_s"].get<double>())
      best = &row;
  }
  ASSERT_NE(best, nullptr);
  EXPECT_EQ(rec["jobs"], (*best)["jobs"]);
  EXPECT_EQ(rec["worker_mode"], (*best)["worker_mode"]);
  EXPECT_EQ(rec["frames_per_s"], (*best)["frames_per_s"]);
  const std::string flags = rec["flags"];
  EXPECT_EQ(flags.rfind("--jobs " + std::to_string((*best)["jobs"].get<int>()) + " --worker-mode " +
                            (*best)["worker_mode"].get<std::string>(),
                        0),
            0u)
      << flags;
  const std::vector<std::string> lines = LinesWith(r.output, "recommended:");
  ASSERT_EQ(lines.size(), 1u) << r.output;
  EXPECT_NE(lines[0].find(flags), std::string::npos) << lines[0];
}

}  // namespace
}  // namespace fetchscope
