// Numbers in pictures (the HUD, contact-sheet captions, probe tiles, the anatomy card): printf
// formatting, except that a value that prints as zero never carries a minus sign. -0.0 (a sparse
// reward on success) and -0.00001 at "%.4f" print "0.0000", not "-0.0000"; with the '+' flag
// "+0.00". JSON output keeps its own formatting (base/json_util.h), -0.0 included.
#pragma once

#include <string>

namespace fetchscope {

/// `value` printed with the printf `format` (one floating-point conversion, e.g. "%.4f m",
/// "%+.2f", "%.3g"); when every digit printed is 0, the value is printed as +0.0 instead, so
/// that a picture never shows "-0". NaN and infinities print as printf prints them.
std::string PictureNumber(const char* format, double value);

/// `part` of `whole` as a percentage a reader can trust: "100%" only when part == whole, "0%"
/// only when part is 0, whole numbers where exact, else one decimal (rounded) that never reads
/// 100 or 0 ("66.7%", "99.7%", "99.9%" for 9999 of 10000, "0.1%"). "100%" when whole is 0.
std::string PercentText(long part, long whole);

}  // namespace fetchscope
