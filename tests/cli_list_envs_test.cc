// `list-envs`, black box: the eight Fetch v4 ids.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::RunFetchscope;

const char* kIds[] = {"FetchReach-v4",     "FetchReachDense-v4",   "FetchPush-v4",
                      "FetchPushDense-v4", "FetchPickAndPlace-v4", "FetchPickAndPlaceDense-v4",
                      "FetchSlide-v4",     "FetchSlideDense-v4"};

TEST(Cli, ListEnvsJsonHasTheEightIds) {
  auto r = RunFetchscope("list-envs --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j.size(), 8u);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(j[i]["id"], kIds[i]);
}

}  // namespace
}  // namespace fetchscope
