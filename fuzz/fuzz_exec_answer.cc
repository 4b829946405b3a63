// libFuzzer target: the exec-policy protocol, one answer line from the child
// (4 numbers separated by spaces or commas, or a JSON array of 4).
#include <cmath>

#include "fuzz/fuzz_common.h"
#include "src/exec_policy.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fetchscope::fuzz::ExpectOnlyOurErrors([&] {
    const auto action = fetchscope::ParseActionLine(fetchscope::fuzz::AsString(data, size));
    for (double v : action) {
      if (!std::isfinite(v)) __builtin_trap();  // documented: 4 finite numbers
    }
  });
  return 0;
}
