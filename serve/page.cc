// The page serve serves: apart from server.cc, so that the router (and its fuzzer) builds without
// the report's page code.
#include "inspect/html_page.h"
#include "serve/server.h"

namespace fetchscope::serve {

std::string ServePage(const Api& api) {
  return HtmlPage(PageKind::kServe, "fetchscope serve", api.PageData());
}

}  // namespace fetchscope::serve
