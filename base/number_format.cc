#include "base/number_format.h"

#include <algorithm>
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

std::string PercentText(long part, long whole) {
  if (whole <= 0 || part >= whole) return "100%";
  if (part <= 0) return "0%";
  char text[32];
  if ((part * 100) % whole == 0) {
    std::snprintf(text, sizeof(text), "%ld%%", part * 100 / whole);
    return text;
  }
  // tenths, rounded, then kept off the ends: never 100.0 for a shortfall nor 0.0 for a part
  long tenths = (part * 2000 + whole) / (2 * whole);
  tenths = std::min(999L, std::max(1L, tenths));
  std::snprintf(text, sizeof(text), "%ld.%ld%%", tenths / 10, tenths % 10);
  return text;
}

}  // namespace fetchscope
