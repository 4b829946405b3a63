// `list-cameras`, black box: aligned columns.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::RunFetchscope;
using testing::SplitLines;

TEST(ListCameras, SecondColumnStartsAtTheSamePlaceOnEveryRow) {
  const CommandResult r = RunFetchscope("list-cameras --env-id FetchPush-v4");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<std::string> lines = SplitLines(r.output);
  ASSERT_GE(lines.size(), 5u) << r.output;  // default, track, free and the model's cameras
  size_t start = std::string::npos;
  for (const std::string& line : lines) {
    const size_t gap = line.find("  ");
    ASSERT_NE(gap, std::string::npos) << line;
    const size_t column = line.find_first_not_of(' ', gap);
    if (start == std::string::npos) start = column;
    EXPECT_EQ(column, start) << r.output;
  }
  EXPECT_NE(r.output.find("head_camera_rgb"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace fetchscope
