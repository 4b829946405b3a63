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

}  // namespace fetchscope
