// libFuzzer target: the --camera spec parser against the bundled Reach model (loaded once),
// then the MuJoCo camera for every parsed spec.
#include <mujoco/mujoco.h>

#include <cstdio>
#include <cstdlib>

#include "fuzz/fuzz_common.h"
#include "render/camera.h"
#include "src/mj_handles.h"

namespace {

const mjModel* ReachModel() {
  static const fetchscope::MjModelPtr model = [] {
    char error[1000] = "";
    fetchscope::MjModelPtr m(
        mj_loadXML(FETCHSCOPE_SOURCE_DIR "/models/reach.xml", nullptr, error, sizeof(error)));
    if (!m) {
      std::fprintf(stderr, "fuzz_camera: cannot load the bundled reach model: %s\n", error);
      std::exit(1);
    }
    return m;
  }();
  return model.get();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const mjModel* model = ReachModel();
  fetchscope::fuzz::ExpectOnlyOurErrors([&] {
    const auto specs = fetchscope::ParseCameraList(fetchscope::fuzz::AsString(data, size), model);
    if (specs.empty()) __builtin_trap();  // documented: one or more cameras, or UsageError
    for (const auto& spec : specs) (void)fetchscope::ToMjvCamera(spec, model);
  });
  return 0;
}
