#include "inspect/html_page.h"

#include <cmath>

#include "web_compare_js.h"
#include "web_page_css.h"
#include "web_page_js.h"
#include "web_report_js.h"
#include "web_serve_js.h"
#include "web_serve_tools_js.h"
#include "web_uplot_css.h"
#include "web_uplot_js.h"
#include "web_viewer_js.h"

namespace fetchscope {
namespace {

std::string Text(const unsigned char* bytes, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(bytes), size);
}

// Text that goes inside <script>: "</" is written "<\/" (the same string to JavaScript and to
// JSON), so no "</script>" in the data or a library can end the element early.
std::string ScriptSafe(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    out += text[i];
    if (text[i] == '<' && i + 1 < text.size() && text[i + 1] == '/') out += '\\';
  }
  return out;
}

std::string HtmlEscape(const std::string& text) { return EscapeMarkup(text, false); }

}  // namespace

const char* EmbeddedUplotVersion() { return FETCHSCOPE_UPLOT_VERSION; }

std::pair<double, double> WilsonInterval(int successes, int n, double z) {
  if (n <= 0) return {0.0, 1.0};
  const double p = static_cast<double>(successes) / n;
  const double z2 = z * z;
  const double denominator = 1 + z2 / n;
  const double centre = (p + z2 / (2.0 * n)) / denominator;
  const double half = z / denominator * std::sqrt(p * (1 - p) / n + z2 / (4.0 * n * n));
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

std::string HtmlPage(PageKind kind, const std::string& title, const nlohmann::json& data,
                     const std::vector<std::pair<std::string, std::string>>& blocks) {
  const std::string page_js = Text(kWebPageJs, kWebPageJs_size);
  const std::string viewer_js = Text(kWebViewerJs, kWebViewerJs_size);
  const std::string kind_js = kind == PageKind::kReport ? Text(kWebReportJs, kWebReportJs_size)
                              : kind == PageKind::kCompare
                                  ? Text(kWebCompareJs, kWebCompareJs_size)
                                  : Text(kWebServeToolsJs, kWebServeToolsJs_size) + "\n" +
                                        Text(kWebServeJs, kWebServeJs_size);
  std::string html;
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  // nothing is fetched from anywhere: the page's own files (videos, sheets) are all it loads;
  // serve's page asks its own server for frames (blob: images) and data
  html += kind == PageKind::kServe
              ? "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'self'; "
                "script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src 'self' blob: "
                "data:; connect-src 'self'\">\n"
              : "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'self'; "
                "script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src 'self' data:; "
                "media-src 'self'\">\n";
  html += "<meta name=\"generator\" content=\"fetchscope " FETCHSCOPE_VERSION "\">\n";
  html += "<title>" + HtmlEscape(title) + "</title>\n";
  // an empty icon, so that a web server is not asked for /favicon.ico
  html += "<link rel=\"icon\" href=\"data:,\">\n";
  html += "<!-- uPlot " FETCHSCOPE_UPLOT_VERSION " (MIT, https://github.com/leeoniya/uPlot) -->\n";
  html += "<style>\n" + Text(kWebUplotCss, kWebUplotCss_size) + "\n</style>\n";
  html += "<style>\n" + Text(kWebPageCss, kWebPageCss_size) + "\n</style>\n";
  html +=
      "</head>\n<body>\n<noscript>This page draws its tables and plots with JavaScript; the "
      "files it shows sit beside it.</noscript>\n<main id=\"page\"></main>\n";
  html += "<script id=\"fetchscope-data\" type=\"application/json\">" + ScriptSafe(data.dump()) +
          "</script>\n";
  // raw text to the HTML parser: no script is compiled until the page parses one
  for (const auto& [id, json_text] : blocks) {
    html += "<script id=\"" + HtmlEscape(id) + "\" type=\"application/json\">" +
            ScriptSafe(json_text) + "</script>\n";
  }
  html += "<script>\n" + ScriptSafe(Text(kWebUplotJs, kWebUplotJs_size)) + "\n</script>\n";
  html += "<script>\n" + ScriptSafe(page_js) + "\n" + ScriptSafe(viewer_js) + "\n" +
          ScriptSafe(kind_js) + "\n</script>\n";
  html += "</body>\n</html>\n";
  return html;
}

std::string EscapeMarkup(const std::string& text, bool xml) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += xml ? "&apos;" : "'";
        break;
      default:
        out += xml && static_cast<unsigned char>(c) < 0x20 && c != '\n' && c != '\t' ? '?' : c;
    }
  }
  return out;
}

}  // namespace fetchscope
