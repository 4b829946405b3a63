// The self-contained HTML pages of `report` and `compare`: one file that inlines uPlot (embedded
// into the binary at build time from web/node_modules, see cli/CMakeLists.txt), the pages' own
// script and style (web/src/) and the data as JSON, so that it opens offline from file:// or any
// static server and fetches nothing.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace fetchscope {

/// Which script draws the page from its data.
enum class PageKind {
  kReport,   ///< a run's index.html (web/src/report.js)
  kCompare,  ///< compare's page (web/src/compare.js)
  kServe,  ///< serve's live page (web/src/serve.js): it also loads frames and data from its server
};

/// The whole HTML text of a page titled `title` whose script renders `data`; each of `blocks`
/// ({element id, JSON text}) is written as a JSON element that the page parses only when it
/// needs it (the episode viewer's per-step data).
std::string HtmlPage(PageKind kind, const std::string& title, const nlohmann::json& data,
                     const std::vector<std::pair<std::string, std::string>>& blocks = {});

/// The uPlot version embedded (from web/package.json at build time), for the page footer.
const char* EmbeddedUplotVersion();

/// Wilson score interval of a binomial proportion: `successes` of `n`, z = 1.96 (95 %).
/// Returns {low, high}; {0, 1} when n is 0.
std::pair<double, double> WilsonInterval(int successes, int n, double z = 1.959963984540054);

/// `text` for HTML text and attribute values: & < > " escaped. With `xml` (XML 1.0, JUnit) also
/// ' as &apos;, and control characters other than newline and tab, which XML refuses, as '?'.
std::string EscapeMarkup(const std::string& text, bool xml);

}  // namespace fetchscope
