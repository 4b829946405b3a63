#include "base/json_util.h"

#include <charconv>
#include <cmath>
#include <cstdlib>

#include "base/atomic_file.h"

namespace fetchscope {
namespace {

std::string DumpScalar(const nlohmann::json& value) {
  return value.dump(-1, ' ', /*ensure_ascii=*/false, nlohmann::json::error_handler_t::replace);
}

void NewLine(int indent, int depth, std::string& out) {
  if (indent < 0) return;
  out.push_back('\n');
  out.append(static_cast<size_t>(indent) * static_cast<size_t>(depth), ' ');
}

// The same layout as nlohmann's serializer: "[\n  1,\n  2\n]", "{}" / "[]" when empty.
void Write(const nlohmann::json& value, int indent, int depth, std::string& out) {
  switch (value.type()) {
    case nlohmann::json::value_t::object: {
      if (value.empty()) {
        out += "{}";
        return;
      }
      out.push_back('{');
      bool first = true;
      for (auto it = value.begin(); it != value.end(); ++it) {
        if (!first) out.push_back(',');
        first = false;
        NewLine(indent, depth + 1, out);
        out += DumpScalar(nlohmann::json(it.key()));
        out += indent < 0 ? ":" : ": ";
        Write(it.value(), indent, depth + 1, out);
      }
      NewLine(indent, depth, out);
      out.push_back('}');
      return;
    }
    case nlohmann::json::value_t::array: {
      if (value.empty()) {
        out += "[]";
        return;
      }
      out.push_back('[');
      bool first = true;
      for (const auto& element : value) {
        if (!first) out.push_back(',');
        first = false;
        NewLine(indent, depth + 1, out);
        Write(element, indent, depth + 1, out);
      }
      NewLine(indent, depth, out);
      out.push_back(']');
      return;
    }
    case nlohmann::json::value_t::number_float: {
      const double v = value.get<double>();
      out += std::isfinite(v) ? FormatDouble(v) : DumpScalar(JsonDouble(v));
      return;
    }
    default:
      out += DumpScalar(value);
      return;
  }
}

}  // namespace

nlohmann::json JsonDouble(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return value;
}

nlohmann::json JsonVector(const double* values, size_t size) {
  nlohmann::json array = nlohmann::json::array();
  for (size_t i = 0; i < size; ++i) array.push_back(JsonDouble(values[i]));
  return array;
}

std::string FormatDouble(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";

  // shortest round-trip digits, in the form [-]d[.ddd]e(+|-)XX
  char buffer[64];
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::scientific);
  const std::string scientific(buffer, result.ptr);
  const size_t e = scientific.find('e');
  const bool negative = scientific[0] == '-';
  std::string digits;
  for (size_t i = negative ? 1 : 0; i < e; ++i) {
    if (scientific[i] != '.') digits.push_back(scientific[i]);
  }
  const int exponent = std::atoi(scientific.c_str() + e + 1);
  // value = 0.<digits> * 10^point, as in Python's float_repr_style 'short'
  const int point = exponent + 1;

  std::string out = negative ? "-" : "";
  if (point > -4 && point <= 16) {
    const int n = static_cast<int>(digits.size());
    if (point <= 0) {
      out += "0." + std::string(static_cast<size_t>(-point), '0') + digits;
    } else if (point >= n) {
      out += digits + std::string(static_cast<size_t>(point - n), '0') + ".0";
    } else {
      out += digits.substr(0, static_cast<size_t>(point)) + "." +
             digits.substr(static_cast<size_t>(point));
    }
  } else {
    out += digits.substr(0, 1);
    if (digits.size() > 1) out += "." + digits.substr(1);
    out += scientific.substr(e);  // to_chars writes "e+XX" / "e-XXX" like Python
  }
  return out;
}

std::string DumpJson(const nlohmann::json& value, int indent) {
  std::string out;
  Write(value, indent, 0, out);
  return out;
}

void WriteJson(const std::string& path, const nlohmann::json& json) {
  WriteFileAtomically(path, DumpJson(json) + "\n");
}

}  // namespace fetchscope
