// JSON output helpers: strict RFC 8259, and doubles written as Python writes them.
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

namespace fetchscope {

/// A double as JSON: finite values as numbers (-0.0 stays -0.0), +inf as "inf", -inf as "-inf"
/// and NaN as "nan" (strings: JSON has no literal for them, and nlohmann would write null).
nlohmann::json JsonDouble(double value);

/// An array of `size` doubles, each as JsonDouble.
nlohmann::json JsonVector(const double* values, size_t size);

/// A finite double exactly as Python's repr() and json.dumps write it: the shortest digits that
/// round-trip, fixed notation for 1e-4 <= |x| < 1e16 (always with a '.', e.g. "1.0", "-0.0"),
/// otherwise "d.ddde+XX" (e.g. "1e+16", "5e-324"). Non-finite values give "nan", "inf", "-inf".
std::string FormatDouble(double value);

/// Serialises `value` like nlohmann's dump(indent) (`indent` < 0: one line; same layout and
/// string escaping), except that doubles are written by FormatDouble, so they are the shortest
/// round-trip form and textually identical to Python's json.dumps. (nlohmann's own Grisu2 output
/// always round-trips but is not always shortest, e.g. 4.1752050594835004e+78.) A non-finite
/// number left in the tree is written as JsonDouble writes it, never as null. Invalid UTF-8 in
/// strings becomes U+FFFD rather than an exception. No trailing newline.
std::string DumpJson(const nlohmann::json& value, int indent = 2);

/// Writes `json` (DumpJson) with a trailing newline to `path` atomically: a temporary name, then a
/// rename, so the file appears whole or not at all. Throws RunError naming the path.
void WriteJson(const std::string& path, const nlohmann::json& json);

}  // namespace fetchscope
