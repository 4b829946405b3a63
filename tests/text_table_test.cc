// Aligned text columns (base/text_table.h).
#include "base/text_table.h"

#include <gtest/gtest.h>

namespace fetchscope {
namespace {

TEST(AlignColumns, PadsEveryColumnButTheLast) {
  EXPECT_EQ(AlignColumns({{"a", "x"}, {"long name", "y"}, {"b"}}),
            "a          x\nlong name  y\nb\n");
  EXPECT_EQ(AlignColumns({{"\xC3\xA9", "x"}, {"ab", "y"}}), "\xC3\xA9   x\nab  y\n");  // é
}

}  // namespace
}  // namespace fetchscope
