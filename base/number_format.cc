#include "base/number_format.h"

#include <cctype>
#include <cstdio>

namespace fetchscope {
namespace {

std::string Printed(const char* format, double value) {
  char buf[128];
  std::snprintf(buf, sizeof(buf), format, value);
  return buf;
}

// True when `text` holds a minus sign and digits, every one of them 0 ("-0", "-0.000",
// "-0.00e+00"): a negative value too small to show, or -0.0 itself.
bool NegativeZero(const std::string& text) {
  bool minus = false, digit = false;
  for (char c : text) {
    if (c == '-' && !digit) minus = true;
    if (std::isdigit(static_cast<unsigned char>(c))) {
      if (c != '0') return false;
      digit = true;
    }
  }
  return minus && digit;
}

}  // namespace

std::string PictureNumber(const char* format, double value) {
  const std::string text = Printed(format, value);
  return NegativeZero(text) ? Printed(format, 0.0) : text;
}

}  // namespace fetchscope
