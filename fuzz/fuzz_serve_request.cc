// libFuzzer target: serve's request parameters (serve/request.h), from a query string split on
// '&' and the first '=' of each pair, as the HTTP library hands them over: every request type is
// parsed; a RequestError (a 4xx for the page) is the documented answer, anything else a finding,
// and so is a parsed request that breaks the limits the engine relies on.
#include <cstdlib>

#include "fuzz/fuzz_common.h"
#include "render/frame_limits.h"
#include "serve/request.h"

namespace {

fetchscope::serve::Query Split(const std::string& text) {
  fetchscope::serve::Query query;
  size_t at = 0;
  while (at <= text.size()) {
    size_t end = text.find('&', at);
    if (end == std::string::npos) end = text.size();
    const std::string pair = text.substr(at, end - at);
    const size_t eq = pair.find('=');
    query.emplace(pair.substr(0, eq), eq == std::string::npos ? "" : pair.substr(eq + 1));
    at = end + 1;
  }
  return query;
}

template <typename Body>
void Expect(Body&& body) {
  try {
    fetchscope::fuzz::ExpectOnlyOurErrors(body);
  } catch (const fetchscope::serve::RequestError& e) {
    if (e.status() < 400 || e.status() > 499) std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fetchscope::serve;
  const Query query = Split(fetchscope::fuzz::AsString(data, size));
  Expect([&] {
    const ViewRequest v = ParseViewRequest(query);
    if (v.width < 1 || v.height < 1 || v.width > kMaxFrameSideLive ||
        static_cast<int64_t>(v.width) * v.height > fetchscope::kMaxFramePixels || v.quality < 1 ||
        v.quality > 100 || v.camera.size() > kMaxParameterBytes ||
        (v.at.source < 0 && v.at.source != kLiveSource) || v.at.episode < 0 || v.at.step < 0) {
      std::abort();
    }
  });
  Expect([&] {
    const PickRequest p = ParsePickRequest(query);
    if (p.x < 0 || p.y < 0 || p.x >= p.view.width || p.y >= p.view.height) std::abort();
  });
  Expect([&] {
    const StepRequest s = ParseStepRequest(query);
    for (int i = 0; s.action && i < 4; ++i) {
      if (!((*s.action)[i] >= -1 && (*s.action)[i] <= 1)) std::abort();
    }
  });
  Expect([&] { (void)ParseStartRequest(query); });
  Expect([&] { (void)ParseEpisodeRequest(query); });
  Expect([&] { (void)SessionParam(query); });
  return 0;
}
