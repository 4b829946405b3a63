// libFuzzer target: the --overlay spec parser, then the HUD text for the parsed set.
#include "fuzz/fuzz_common.h"
#include "render/overlay.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fetchscope::fuzz::ExpectOnlyOurErrors([&] {
    const fetchscope::OverlaySet set =
        fetchscope::ParseOverlays(fetchscope::fuzz::AsString(data, size));
    fetchscope::FrameInfo info;
    info.step = 3;
    info.reward = -0.5;
    info.has_action = true;
    info.action = {1, -1, 0.5, 0};
    info.title = "FetchReach-v4";
    (void)fetchscope::FormatHud(info, set);
  });
  return 0;
}
