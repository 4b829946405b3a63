// `reward-check`, black box: every task passes on the bundled and the genuine assets.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::RunFetchscope;

TEST(Cli, RewardCheckPassesForEveryTaskBundledAndGenuine) {
  std::vector<std::string> assets = {"bundled"};
  if (!testing::GenuineAssetsDir().empty()) assets.push_back(testing::GenuineAssetsDir().string());
  for (const std::string& a : assets) {
    for (const char* id :
         {"FetchReach-v4", "FetchPushDense-v4", "FetchPickAndPlace-v4", "FetchSlide-v4"}) {
      auto r = RunFetchscope(std::string("reward-check --n-steps 500 --env-id ") + id +
                             " --assets " + a);
      EXPECT_EQ(r.exit_code, 0) << id << " " << a << "\n" << r.output;
      EXPECT_NE(r.output.find("PASS"), std::string::npos);
      EXPECT_NE(r.output.find("Dense-v4"), std::string::npos);  // both variants checked
    }
  }
}

}  // namespace
}  // namespace fetchscope
