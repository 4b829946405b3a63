// Numbers in pictures (base/number_format.h): no "-0", otherwise as printf prints them.
#include "base/number_format.h"

#include <gtest/gtest.h>

namespace fetchscope {
namespace {

TEST(PictureNumber, NegativeZeroPrintsAsZero) {
  EXPECT_EQ(PictureNumber("%.4f", -0.0), "0.0000");
  EXPECT_EQ(PictureNumber("%.4f", -0.00001), "0.0000");  // rounds to zero
  EXPECT_EQ(PictureNumber("%.3g", -0.0), "0");
  EXPECT_EQ(PictureNumber(" r=%.3g", -0.0), " r=0");
  EXPECT_EQ(PictureNumber("%+.2f", -0.001), "+0.00");
  EXPECT_EQ(PictureNumber("%.2e", -0.0), "0.00e+00");
  EXPECT_EQ(PictureNumber("%.4f m", -0.0), "0.0000 m");
}

TEST(PictureNumber, OtherValuesPrintAsPrintfDoes) {
  EXPECT_EQ(PictureNumber("%.4f", -0.5), "-0.5000");
  EXPECT_EQ(PictureNumber("%.3g", -1.0), "-1");
  EXPECT_EQ(PictureNumber("%+.2f", 0.25), "+0.25");
  EXPECT_EQ(PictureNumber("%+.2f", -0.006), "-0.01");
  EXPECT_EQ(PictureNumber("%.2e", -1e-5), "-1.00e-05");  // the exponent's minus is no sign
  EXPECT_EQ(PictureNumber("%.4f", 0.0), "0.0000");
}

}  // namespace
}  // namespace fetchscope
