#include "src/replay_file.h"

#include <locale.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "base/confined_file.h"
#include "base/errors.h"

namespace fetchscope {
namespace {

constexpr size_t kActionSize = 4;

// "replay file NAME[ WHERE]: WHAT" as a RunError.
[[noreturn]] void Fail(const std::string& name, const std::string& where, const std::string& what) {
  throw RunError("replay file " + name + (where.empty() ? "" : " " + where) + ": " + what);
}

// A value quoted for an error message: one line, printable, not too long (the input may be
// binary garbage).
std::string Quote(const std::string& value) {
  constexpr size_t kMaxShown = 32;
  std::string out = "'";
  for (size_t i = 0; i < value.size() && i < kMaxShown; ++i) {
    const unsigned char c = static_cast<unsigned char>(value[i]);
    if (c >= 0x20 && c < 0x7f && c != '\'' && c != '\\') {
      out.push_back(static_cast<char>(c));
    } else {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\x%02x", c);
      out += escaped;
    }
  }
  if (value.size() > kMaxShown) out += "...";
  return out + "'";
}

std::string Trim(const std::string& s) {
  const char* kSpace = " \t\r\v\f";
  const size_t begin = s.find_first_not_of(kSpace);
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(kSpace) - begin + 1);
}

// Splits into lines on '\n'; a trailing '\r' stays (Trim removes it).
std::vector<std::string> SplitLines(const std::string& text) {
  std::vector<std::string> lines;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

// Parses a whole field as a double; false if it is not a number.
bool ParseDouble(const std::string& field, double* value) {
  if (field.empty() || field.find('\0') != std::string::npos) return false;
  const char* begin = field.c_str();
  char* end = nullptr;
  errno = 0;
  // strtod in the "C" locale: a caller's setlocale() must not turn "0.5" into 0
  static const locale_t c_locale = ::newlocale(LC_ALL_MASK, "C", static_cast<locale_t>(0));
  *value = ::strtod_l(begin, &end, c_locale);
  return end == begin + field.size();
}

void CheckFinite(double value, const std::string& shown, const std::string& name,
                 const std::string& where) {
  if (!std::isfinite(value)) {
    Fail(name, where,
         "value " + shown + " is not a finite number (NaN and infinities are rejected)");
  }
}

void CheckNotEmpty(const std::vector<Action>& actions, const std::string& name) {
  if (actions.empty())
    throw RunError("replay file " + name + " is empty: expected at least one action row");
}

// Printable ASCII or UTF-8 (no control bytes): binary garbage is not taken for a header.
bool IsPrintableText(const std::string& line) {
  return std::none_of(line.begin(), line.end(), [](char ch) {
    const unsigned char c = static_cast<unsigned char>(ch);
    return (c < 0x20 && c != '\t') || c == 0x7f;
  });
}

// "1 2 3 4" or "0.5x" are broken numbers, not header words.
bool StartsLikeNumber(const std::string& field) {
  size_t i = 0;
  if (i < field.size() && (field[i] == '+' || field[i] == '-')) ++i;
  if (i < field.size() && field[i] == '.') ++i;
  return i < field.size() && std::isdigit(static_cast<unsigned char>(field[i]));
}

// ---- CSV -------------------------------------------------------------------------------------

std::vector<Action> ParseCsv(std::string text, const std::string& name) {
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);  // UTF-8 BOM from spreadsheets
  std::vector<Action> actions;
  bool seen_content = false;
  const std::vector<std::string> lines = SplitLines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string line = Trim(lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const std::string where = "line " + std::to_string(i + 1);

    std::vector<std::string> fields;
    std::stringstream stream(line);
    for (std::string field; std::getline(stream, field, ',');) fields.push_back(Trim(field));
    if (line.back() == ',') fields.push_back("");

    const bool first = !seen_content;
    seen_content = true;
    double values[kActionSize];
    bool all_words = true;
    bool any_text = false;
    for (size_t c = 0; c < fields.size(); ++c) {
      double v = 0;  // what ParseDouble leaves on failure does not matter: any_text reports it
      const bool ok = ParseDouble(fields[c], &v);
      if (c < kActionSize) values[c] = v;
      all_words = all_words && !ok && !StartsLikeNumber(fields[c]);
      any_text = any_text || !ok;
    }
    if (first && all_words && IsPrintableText(line)) continue;  // a header: "dx,dy,dz,gripper"
    if (fields.size() != kActionSize) {
      Fail(name, where,
           "expected 4 numbers separated by commas, got " + std::to_string(fields.size()));
    }
    if (any_text) {
      for (const std::string& field : fields) {
        double v;
        if (!ParseDouble(field, &v)) {
          Fail(name, where,
               "value " + Quote(field) + " is not a number" +
                   (first ? "" : " (a header line is allowed only as the first line)"));
        }
      }
    }
    Action action;
    for (size_t c = 0; c < kActionSize; ++c) {
      CheckFinite(values[c], Quote(fields[c]), name, where);
      action.value[c] = values[c];
    }
    actions.push_back(action);
  }
  CheckNotEmpty(actions, name);
  return actions;
}

// ---- JSON lines ------------------------------------------------------------------------------

const char kJsonAccepted[] =
    "expected [dx, dy, dz, gripper] or {\"action\": [dx, dy, dz, gripper]}";

std::string ShowJson(const nlohmann::json& value) {
  return Quote(value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
}

Action JsonRowToAction(const nlohmann::json& row, const std::string& name,
                       const std::string& where) {
  const nlohmann::json* array = &row;
  if (row.is_object()) {
    const auto it = row.find("action");
    if (it == row.end())
      Fail(name, where, std::string("object has no \"action\" member: ") + kJsonAccepted);
    array = &*it;
  }
  if (!array->is_array()) Fail(name, where, "got " + ShowJson(*array) + ": " + kJsonAccepted);
  if (array->size() != kActionSize) {
    Fail(name, where, "expected an array of 4 numbers, got " + std::to_string(array->size()));
  }
  Action action;
  for (size_t c = 0; c < kActionSize; ++c) {
    const nlohmann::json& element = (*array)[c];
    if (!element.is_number()) Fail(name, where, "value " + ShowJson(element) + " is not a number");
    const double v = element.get<double>();
    CheckFinite(v, ShowJson(element), name, where);
    action.value[c] = v;
  }
  return action;
}

std::vector<Action> ParseJsonLines(const std::string& text, const std::string& name) {
  std::vector<Action> actions;

  // A whole document holding an array of rows (json.dump(actions.tolist())).
  const nlohmann::json document = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (document.is_array() && !document.empty() &&
      (document.front().is_array() || document.front().is_object())) {
    for (size_t i = 0; i < document.size(); ++i) {
      actions.push_back(JsonRowToAction(document[i], name, "row index " + std::to_string(i)));
    }
    return actions;
  }

  const std::vector<std::string> lines = SplitLines(text);
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string line = Trim(lines[i]);
    if (line.empty()) continue;
    const std::string where = "line " + std::to_string(i + 1);
    const nlohmann::json row = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
    if (row.is_discarded()) Fail(name, where, "not valid JSON: " + std::string(kJsonAccepted));
    actions.push_back(JsonRowToAction(row, name, where));
  }
  CheckNotEmpty(actions, name);
  return actions;
}

// ---- NPY -------------------------------------------------------------------------------------

const char kNpyMagic[] = "\x93NUMPY";
constexpr size_t kNpyMagicSize = 6;

struct NpyHeader {
  std::string descr;
  bool fortran_order = false;
  std::vector<uint64_t> shape;
};

// Parses the Python dict literal numpy writes, e.g.
//   {'descr': '<f8', 'fortran_order': False, 'shape': (6, 4), }
// Like numpy it requires exactly the three keys.
class NpyHeaderParser {
 public:
  NpyHeaderParser(const std::string& text, const std::string& name) : text_(text), name_(name) {}

  NpyHeader Parse() {
    NpyHeader header;
    bool has_descr = false, has_fortran = false, has_shape = false;
    Expect('{');
    while (!Accept('}')) {
      const std::string key = ParseString();
      Expect(':');
      if (key == "descr") {
        SkipSpace();
        if (pos_ < text_.size() && text_[pos_] == '[') {
          Fail(name_, "",
               ".npy structured dtypes are not supported: use float32 ('<f4') or float64 ('<f8')");
        }
        header.descr = ParseString();
        has_descr = true;
      } else if (key == "fortran_order") {
        header.fortran_order = ParseBool();
        has_fortran = true;
      } else if (key == "shape") {
        header.shape = ParseTuple();
        has_shape = true;
      } else {
        Bad("unexpected key " + Quote(key));
      }
      if (!Accept(',')) {
        Expect('}');
        break;
      }
    }
    if (!has_descr || !has_fortran || !has_shape)
      Bad("'descr', 'fortran_order' or 'shape' is missing");
    return header;
  }

 private:
  [[noreturn]] void Bad(const std::string& what) {
    Fail(name_, "", ".npy header is malformed (" + what + "): write it with numpy.save");
  }
  void SkipSpace() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool Accept(char c) {
    SkipSpace();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  void Expect(char c) {
    if (!Accept(c)) Bad(std::string("expected '") + c + "'");
  }
  std::string ParseString() {
    SkipSpace();
    if (pos_ >= text_.size() || (text_[pos_] != '\'' && text_[pos_] != '"'))
      Bad("expected a string");
    const char quote = text_[pos_++];
    const size_t end = text_.find(quote, pos_);
    if (end == std::string::npos) Bad("unterminated string");
    std::string s = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return s;
  }
  bool ParseBool() {
    SkipSpace();
    for (const char* word : {"True", "False"}) {
      if (text_.compare(pos_, std::strlen(word), word) == 0) {
        pos_ += std::strlen(word);
        return word[0] == 'T';
      }
    }
    Bad("fortran_order is not True or False");
  }
  std::vector<uint64_t> ParseTuple() {
    std::vector<uint64_t> values;
    Expect('(');
    while (!Accept(')')) {
      SkipSpace();
      uint64_t v = 0;
      size_t digits = 0;
      while (pos_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[pos_]))) {
        if (++digits > 18) Bad("shape is too large");
        v = v * 10 + static_cast<uint64_t>(text_[pos_++] - '0');
      }
      if (digits == 0) Bad("shape is not a tuple of integers");
      Accept('L');  // Python 2 longs
      values.push_back(v);
      if (!Accept(',')) {
        Expect(')');
        break;
      }
    }
    return values;
  }

  const std::string& text_;
  const std::string& name_;
  size_t pos_ = 0;
};

std::string ShapeString(const std::vector<uint64_t>& shape) {
  std::string s = "(";
  for (size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
  return s + (shape.size() == 1 ? ",)" : ")");
}

std::string Decimal(unsigned __int128 v) {
  std::string digits;
  do {
    digits.insert(digits.begin(), static_cast<char>('0' + static_cast<int>(v % 10)));
    v /= 10;
  } while (v != 0);
  return digits;
}

uint32_t ReadLittleEndian(const std::string& bytes, size_t offset, size_t size) {
  uint32_t v = 0;
  for (size_t i = 0; i < size; ++i)
    v |= uint32_t{static_cast<unsigned char>(bytes[offset + i])} << (8 * i);
  return v;
}

// The header of a .npy file (versions 1.0-3.0); `data_start` gets where its data begins.
NpyHeader ReadNpyHeader(const std::string& bytes, const std::string& name, size_t* data_start) {
  if (bytes.size() < kNpyMagicSize + 2 ||
      bytes.compare(0, kNpyMagicSize, kNpyMagic, kNpyMagicSize) != 0) {
    Fail(name, "", "not a .npy file (no \\x93NUMPY magic): write it with numpy.save");
  }
  const int major = static_cast<unsigned char>(bytes[kNpyMagicSize]);
  if (major < 1 || major > 3) {
    Fail(name, "",
         ".npy format version " + std::to_string(major) + " is not supported: use 1.0, 2.0 or 3.0");
  }
  const size_t length_size = major == 1 ? 2 : 4;
  const size_t header_start = kNpyMagicSize + 2 + length_size;
  if (bytes.size() < header_start) Fail(name, "", ".npy file is truncated inside its header");
  const size_t header_length = ReadLittleEndian(bytes, kNpyMagicSize + 2, length_size);
  if (bytes.size() - header_start < header_length)
    Fail(name, "", ".npy file is truncated inside its header");

  const std::string header_text = bytes.substr(header_start, header_length);
  *data_start = header_start + header_length;
  return NpyHeaderParser(header_text, name).Parse();
}

// Refuses what a replay cannot take: big-endian or non-float dtypes, Fortran order, a shape
// other than (T, 4).
void CheckNpyHeader(const NpyHeader& header, const std::string& name) {
  if (header.descr == ">f4" || header.descr == ">f8") {
    Fail(name, "",
         ".npy dtype " + Quote(header.descr) +
             " is big-endian: use little-endian float32 ('<f4') or float64 ('<f8')");
  }
  if (header.descr != "<f4" && header.descr != "<f8") {
    Fail(name, "",
         ".npy dtype " + Quote(header.descr) +
             " is not supported: use float32 ('<f4') or float64 ('<f8')");
  }
  if (header.fortran_order) {
    Fail(name, "",
         ".npy array is in Fortran order: save a C-ordered array (numpy.ascontiguousarray)");
  }
  if (header.shape.size() != 2 || header.shape[1] != kActionSize) {
    Fail(name, "",
         ".npy shape " + ShapeString(header.shape) + " is not supported: expected (T, 4)");
  }
}

// `rows` actions of little-endian float32 or float64 values at `data`, each finite.
std::vector<Action> NpyActions(const char* data, uint64_t rows, bool is_float32,
                               const std::string& name) {
  const size_t item_size = is_float32 ? 4 : 8;
  std::vector<Action> actions;
  actions.reserve(rows);
  for (uint64_t r = 0; r < rows; ++r) {
    Action action;
    action.is_float32 = is_float32;
    for (size_t c = 0; c < kActionSize; ++c) {
      const char* p = data + (r * kActionSize + c) * item_size;
      double v;
      // the host is little-endian (x86-64, aarch64), like the data
      if (is_float32) {
        float f;
        std::memcpy(&f, p, sizeof(f));
        v = f;
      } else {
        std::memcpy(&v, p, sizeof(v));
      }
      if (!std::isfinite(v)) {
        std::ostringstream shown;
        shown << v;
        CheckFinite(v, Quote(shown.str()), name,
                    "row index " + std::to_string(r) + " column " + std::to_string(c));
      }
      action.value[c] = v;
    }
    actions.push_back(action);
  }
  return actions;
}

std::vector<Action> ParseNpy(const std::string& bytes, const std::string& name) {
  size_t data_start = 0;
  const NpyHeader header = ReadNpyHeader(bytes, name, &data_start);
  CheckNpyHeader(header, name);

  const bool is_float32 = header.descr == "<f4";
  const size_t item_size = is_float32 ? 4 : 8;
  const size_t row_bytes = kActionSize * item_size;
  const size_t available = bytes.size() - data_start;
  const uint64_t rows = header.shape[0];
  // 128 bits: a corrupt header may claim up to 10^18 rows
  const unsigned __int128 needed = static_cast<unsigned __int128>(rows) * row_bytes;
  if (needed != available) {
    Fail(name, "",
         ".npy shape " + ShapeString(header.shape) + " needs " + Decimal(needed) +
             " bytes of data but the file has " + std::to_string(available) +
             ": it is truncated or corrupt");
  }

  std::vector<Action> actions = NpyActions(bytes.data() + data_start, rows, is_float32, name);
  CheckNotEmpty(actions, name);
  return actions;
}

std::string Lowercase(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

std::vector<Action> ParseReplayText(const std::string& text, const std::string& format,
                                    const std::string& name) {
  if (format == "csv") return ParseCsv(text, name);
  if (format == "npy") return ParseNpy(text, name);
  if (format == "jsonl" || format == "json") return ParseJsonLines(text, name);
  throw RunError("unknown replay format " + Quote(format) + ": use csv, npy or jsonl");
}

std::string ReadReplayBytes(const std::string& path, std::string* format) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  const std::string extension =
      dot == std::string::npos || (slash != std::string::npos && dot < slash)
          ? ""
          : Lowercase(path.substr(dot));
  const char kAccepted[] = ": use .csv, .npy or .jsonl (or .json)";
  if (extension.empty()) throw UsageError("replay file " + path + " has no extension" + kAccepted);
  if (extension != ".csv" && extension != ".npy" && extension != ".jsonl" && extension != ".json") {
    throw UsageError("replay file " + path + ": unknown replay file extension " + Quote(extension) +
                     kAccepted);
  }

  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw UsageError("cannot read replay file " + path + ": it is a folder, not a file");
  }
  // access(), not an open: opening a FIFO would wait for a writer (ReadFileCapped refuses one)
  if (access(path.c_str(), R_OK) != 0) {
    const int error = errno;
    ThrowPathError("cannot read replay file " + path + ": " + std::strerror(error), error);
  }
  std::string contents = ReadFileCapped(path, kMaxJsonFileBytes);
  *format = extension.substr(1);
  return contents;
}

std::vector<Action> ReadReplayFile(const std::string& path) {
  std::string format;
  const std::string bytes = ReadReplayBytes(path, &format);
  return ParseReplayText(bytes, format, path);
}

}  // namespace fetchscope
