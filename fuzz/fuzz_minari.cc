// libFuzzer target: the Minari dataset reader (dataset/minari_reader.h). An input that starts
// with '{' is a metadata.json (ParseMinariMetadata); any other is the bytes of a main_data.hdf5,
// opened in memory (libhdf5's core driver with a file image) and read as a Reach and as an
// object-task dataset of up to three episodes.
#include <hdf5.h>

#include "dataset/minari_reader.h"
#include "fuzz/fuzz_common.h"

// libhdf5 (Debian's, not instrumented) leaks small blocks of its own on some corrupt files;
// whether we leave an HDF5 object open is checked below instead (H5Fget_obj_count)
extern "C" const char* __lsan_default_suppressions() { return "leak:libhdf5_serial.so\n"; }

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input = fetchscope::fuzz::AsString(data, size);
  if (!input.empty() && input.front() == '{') {
    fetchscope::fuzz::ExpectOnlyOurErrors(
        [&] { fetchscope::ParseMinariMetadata(input, "fuzz/metadata.json"); });
    return 0;
  }
  for (int width : {10, 25}) {
    fetchscope::MinariMetadata metadata;
    metadata.obs_dim = width;
    metadata.total_episodes = 3;
    fetchscope::fuzz::ExpectOnlyOurErrors([&] {
      const auto episodes =
          fetchscope::ReadMinariEpisodes("fuzz/main_data.hdf5", metadata, {}, &input);
      // the reader's contract: every array as long as T says
      for (const auto& e : episodes) {
        const size_t t = e.rewards.size();
        if (e.observation.size() != (t + 1) * width || e.achieved_goal.size() != (t + 1) * 3 ||
            e.desired_goal.size() != (t + 1) * 3 || e.actions.size() != t * 4 ||
            e.terminations.size() != t || e.truncations.size() != t ||
            (!e.is_success.empty() && e.is_success.size() != t + 1)) {
          __builtin_trap();
        }
      }
    });
    // every file, group, dataset and attribute the reader opened is closed again
    if (H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL) != 0) __builtin_trap();
  }
  return 0;
}
