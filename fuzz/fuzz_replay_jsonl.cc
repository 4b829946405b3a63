// libFuzzer target: the JSON-lines replay-file parser (--policy replay:FILE.jsonl).
#include <cmath>

#include "fuzz/fuzz_common.h"
#include "src/replay_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fetchscope::fuzz::ExpectOnlyOurErrors([&] {
    const auto actions =
        fetchscope::ParseReplayText(fetchscope::fuzz::AsString(data, size), "jsonl", "fuzz.jsonl");
    // the documented contract: at least one row, every value finite
    if (actions.empty()) __builtin_trap();
    for (const auto& a : actions) {
      for (double v : a.value) {
        if (!std::isfinite(v)) __builtin_trap();
      }
    }
  });
  return 0;
}
