// libFuzzer target: the NPY replay-file parser (--policy replay:FILE.npy): magic, version,
// header dict, dtype, shape and data size.
#include <cmath>

#include "fuzz/fuzz_common.h"
#include "src/replay_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fetchscope::fuzz::ExpectOnlyOurErrors([&] {
    const auto actions =
        fetchscope::ParseReplayText(fetchscope::fuzz::AsString(data, size), "npy", "fuzz.npy");
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
