// Reading recorded actions for `--policy replay:FILE`.
#pragma once

#include <string>
#include <vector>

#include "src/action.h"

namespace fetchscope {

/// Reads a replay file; the format is chosen by the (case-insensitive) extension:
///  - `.csv`: one action per line, 4 numbers separated by commas, parsed in double precision.
///    Blank lines and lines starting with '#' (np.savetxt's header) are ignored; a header line of
///    non-numbers is allowed as the first line only; CRLF line ends and a UTF-8 BOM are accepted.
///  - `.npy`: NPY format 1.0/2.0/3.0, C order, shape (T, 4), dtype '<f4' (actions come out with
///    is_float32 = true and exactly those float values) or '<f8'.
///  - `.jsonl` / `.json`: JSON lines, each non-empty line `[dx, dy, dz, gripper]` or an object with
///    an "action" member holding that array (other members are ignored); a whole document that is
///    one array of such rows (json.dump(actions.tolist())) is accepted too. Double precision.
/// NaN and infinities are rejected; values outside [-1, 1] are kept (the env clips them, as
/// Gymnasium does). At least one row is required. Every problem throws RunError with one line
/// naming the file, the line or row, what was wrong and what is accepted.
std::vector<Action> ReadReplayFile(const std::string& path);

/// The bytes of replay file `path`, read once, and its format (`*format`: "csv", "npy",
/// "jsonl" or "json", from the extension as above). Throws RunError as ReadReplayFile does for
/// a file without a known extension, a folder, or one that cannot be read.
std::string ReadReplayBytes(const std::string& path, std::string* format);

/// Parses the bytes of a replay file. `format` is "csv", "npy", "jsonl" or "json" (as the
/// extensions above); `name` is the file name used in error messages.
std::vector<Action> ParseReplayText(const std::string& text, const std::string& format,
                                    const std::string& name);

}  // namespace fetchscope
