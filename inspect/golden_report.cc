#include "inspect/golden_report.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "base/atomic_file.h"
#include "base/json_util.h"
#include "encode/png_io.h"
#include "inspect/html_page.h"

namespace fs = std::filesystem;

namespace fetchscope {
namespace {

// Text for XML and HTML: the five special characters escaped, control characters (not allowed
// in XML 1.0) as '?'.
std::string Escape(const std::string& s) { return EscapeMarkup(s, true); }

std::string Format(const char* format, double a, double b = 0, double c = 0) {
  char buf[160];
  std::snprintf(buf, sizeof(buf), format, a, b, c);
  return buf;
}

// The numbers of a row in one line: "0.412% of pixels over 8 levels (limit 0.020%), max 17, rms
// 0.61 (limit 1.00); tolerance: same backend".
std::string PixelLine(const GoldenRow& r) {
  if (!r.have_pixels) return "pixels not compared";
  const GoldenTolerance& t = r.tolerance;
  return Format("%.3f%% of pixels over %.0f levels", 100 * r.stats.fraction_over, t.threshold) +
         Format(" (limit %.3f%%), max difference %.0f, rms %.3f", 100 * t.max_fraction,
                r.stats.max_diff, r.stats.rms) +
         Format(" (limit %.3f); tolerance: ", t.max_rms) + r.tolerance_why;
}

// Every line a person needs about a row: verdict, state change, notes, numbers, images.
std::vector<std::string> RowLines(const GoldenRow& r, const std::string& out) {
  std::vector<std::string> lines = {r.scene + ": " + r.verdict};
  if (!r.state_change.empty()) lines.push_back("state: " + r.state_change);
  for (const std::string& n : r.notes) lines.push_back("note: " + n);
  lines.push_back(PixelLine(r));
  for (const std::string* png : {&r.golden_png, &r.actual_png, &r.diff_png, &r.side_png}) {
    if (!png->empty()) lines.push_back("image: " + (fs::path(out) / *png).string());
  }
  return lines;
}

size_t Count(const GoldenRun& run, const char* status) {
  return std::count_if(run.rows.begin(), run.rows.end(),
                       [&](const GoldenRow& r) { return r.status == status; });
}

nlohmann::json RowJson(const GoldenRow& r) {
  nlohmann::json j = {{"scene", r.scene},
                      {"status", r.status},
                      {"verdict", r.verdict},
                      {"notes", r.notes},
                      {"state_change", r.state_change},
                      {"seconds", JsonDouble(r.seconds)}};
  if (r.have_pixels) {
    j["pixels"] = {{"fraction_over", JsonDouble(r.stats.fraction_over)},
                   {"pixels_over", r.stats.pixels_over},
                   {"max_diff", r.stats.max_diff},
                   {"rms", JsonDouble(r.stats.rms)}};
    j["tolerance"] = {{"threshold", r.tolerance.threshold},
                      {"max_fraction", JsonDouble(r.tolerance.max_fraction)},
                      {"max_rms", JsonDouble(r.tolerance.max_rms)},
                      {"why", r.tolerance_why}};
  }
  if (r.region.width > 0) {
    j["changed_region"] = {{"x", r.region.x},
                           {"y", r.region.y},
                           {"width", r.region.width},
                           {"height", r.region.height}};
  }
  nlohmann::json images = nlohmann::json::object();
  if (!r.golden_png.empty()) images["golden"] = r.golden_png;
  if (!r.actual_png.empty()) images["actual"] = r.actual_png;
  if (!r.diff_png.empty()) images["diff"] = r.diff_png;
  if (!r.side_png.empty()) images["side"] = r.side_png;
  j["images"] = images;
  return j;
}

// One panel of the page: the image, and the changed region's box over it (scaled with it).
std::string Panel(const GoldenRow& r, const std::string& png, const char* label) {
  std::string box;
  if (r.region.width > 0 && r.width > 0 && r.height > 0) {
    box = "<div class=\"box\" style=\"" +
          Format("left:%.3f%%;top:%.3f%%;", 100.0 * r.region.x / r.width,
                 100.0 * r.region.y / r.height) +
          Format("width:%.3f%%;height:%.3f%%\"></div>", 100.0 * r.region.width / r.width,
                 100.0 * r.region.height / r.height);
  }
  return std::string("<figure><figcaption>") + label + "</figcaption><div class=\"frame\">" +
         "<img src=\"" + Escape(png) + "\" alt=\"" + label + "\">" + box + "</div></figure>";
}

constexpr char kStyle[] =
    "body{font:14px system-ui,sans-serif;margin:1.5em;background:#fafafa;color:#222}"
    "section{background:#fff;border:1px solid #ddd;border-radius:6px;padding:1em;margin:1em 0}"
    "h2{margin:0 0 .4em;font-size:1.1em}.fail h2{color:#b00020}.error h2{color:#8a4b00}"
    ".panels{display:flex;gap:12px;flex-wrap:wrap}figure{margin:0}"
    "figcaption{font-weight:600;margin-bottom:4px}.frame{position:relative;display:inline-block}"
    ".frame img{display:block;width:320px;image-rendering:pixelated}"
    ".box{position:absolute;border:2px solid #00e5ff;box-shadow:0 0 0 1px #000;"
    "box-sizing:border-box}.scale img{width:256px;height:14px;display:block}"
    ".ticks{display:flex;justify-content:space-between;width:256px;font-size:11px}"
    "ul{margin:.3em 0 .3em 1.2em;padding:0}code{background:#eee;padding:0 3px}";

std::string SceneSection(const GoldenRow& r) {
  std::ostringstream h;
  h << "<section class=\"" << Escape(r.status) << "\" id=\"scene-" << Escape(r.scene) << "\">"
    << "<h2>" << Escape(r.scene) << " — " << Escape(r.verdict) << "</h2><ul>";
  if (!r.state_change.empty()) h << "<li>state: " << Escape(r.state_change) << "</li>";
  for (const std::string& n : r.notes) h << "<li>" << Escape(n) << "</li>";
  h << "<li>" << Escape(PixelLine(r)) << "</li>";
  if (r.region.width > 0) {
    h << "<li>pixels over the threshold (box): " << r.region.width << "x" << r.region.height
      << " at (" << r.region.x << ", " << r.region.y << ")</li>";
  }
  h << "</ul><div class=\"panels\">";
  if (!r.golden_png.empty()) h << Panel(r, r.golden_png, "golden");
  if (!r.actual_png.empty()) h << Panel(r, r.actual_png, "actual");
  if (!r.diff_png.empty()) h << Panel(r, r.diff_png, "diff");
  h << "</div></section>\n";
  return h.str();
}

}  // namespace

ChangedRegion FindChangedRegion(const uint8_t* golden, const uint8_t* actual, int width, int height,
                                int threshold) {
  for (const int limit : {threshold, 0}) {
    int x0 = width, y0 = height, x1 = -1, y1 = -1;
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const size_t at = (static_cast<size_t>(y) * width + x) * 3;
        int d = 0;
        for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(golden[at + c] - actual[at + c]));
        if (d <= limit) continue;
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
    }
    if (x1 >= 0) return {x0, y0, x1 - x0 + 1, y1 - y0 + 1};
  }
  return {};
}

void PrintGoldenTable(const std::vector<GoldenRow>& rows) {
  size_t name_width = 5;
  for (const GoldenRow& r : rows) name_width = std::max(name_width, r.scene.size());
  // every column named: "result" is ok, FAIL, ERROR or skip
  std::printf("%-*s  %-6s  %9s %8s  %4s  %6s %6s  %s\n", static_cast<int>(name_width), "scene",
              "result", "over thr", "limit", "max", "rms", "limit", "verdict");
  for (const GoldenRow& r : rows) {
    const GoldenTolerance& t = r.tolerance;
    char over[32] = "-", limit[32] = "-", max[16] = "-", rms[16] = "-", rms_limit[16] = "-";
    if (r.have_pixels) {
      std::snprintf(over, sizeof(over), "%.3f%%", 100 * r.stats.fraction_over);
      std::snprintf(limit, sizeof(limit), "%.3f%%", 100 * t.max_fraction);
      std::snprintf(max, sizeof(max), "%d", r.stats.max_diff);
      std::snprintf(rms, sizeof(rms), "%.3f", r.stats.rms);
      std::snprintf(rms_limit, sizeof(rms_limit), "%.3f", t.max_rms);
    }
    const char* result = r.status == "pass"    ? "ok"
                         : r.status == "fail"  ? "FAIL"
                         : r.status == "error" ? "ERROR"
                                               : "skip";
    std::printf("%-*s  %-6s  %9s %8s  %4s  %6s %6s  %s\n", static_cast<int>(name_width),
                r.scene.c_str(), result, over, limit, max, rms, rms_limit, r.verdict.c_str());
  }
  for (const GoldenRow& r : rows) {
    if (!r.state_change.empty()) {
      std::printf("  %s: state: %s\n", r.scene.c_str(), r.state_change.c_str());
    }
    for (const std::string& n : r.notes) {
      if (n.rfind("these goldens record no metadata", 0) == 0) continue;  // said once above
      std::printf("  %s: %s\n", r.scene.c_str(), n.c_str());
    }
  }
}

void WriteGoldenJunit(const std::string& path, const GoldenRun& run) {
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites>\n"
    << "  <testsuite name=\"fetchscope golden " << Escape(run.command) << "\" tests=\""
    << run.rows.size() << "\" failures=\"" << Count(run, "fail") << "\" errors=\""
    << Count(run, "error") << "\" skipped=\"" << Count(run, "skipped") << "\">\n";
  for (const GoldenRow& r : run.rows) {
    x << "    <testcase classname=\"golden\" name=\"" << Escape(r.scene)
      << Format("\" time=\"%.3f\"", r.seconds) << ">";
    std::string text;
    for (const std::string& line : RowLines(r, run.out)) text += line + "\n";
    if (r.status == "fail" || r.status == "error") {
      const char* tag = r.status == "fail" ? "failure" : "error";
      x << "\n      <" << tag << " message=\"" << Escape(r.verdict) << "\">" << Escape(text) << "</"
        << tag << ">\n    ";
    } else if (r.status == "skipped") {
      x << "<skipped message=\"" << Escape(r.verdict) << "\"/>";
    }
    x << "</testcase>\n";
  }
  x << "  </testsuite>\n</testsuites>\n";
  WriteFileAtomically(path, x.str());
}

void WriteGoldenJson(const std::string& path, const GoldenRun& run) {
  nlohmann::json j = {{"command", run.command},           {"manifest", run.manifest},
                      {"running_on", run.running_on},     {"passed", Count(run, "pass")},
                      {"failed", Count(run, "fail")},     {"errors", Count(run, "error")},
                      {"skipped", Count(run, "skipped")}, {"scenes", nlohmann::json::array()}};
  for (const GoldenRow& r : run.rows) j["scenes"].push_back(RowJson(r));
  WriteJson(path, j);
}

std::string WriteGoldenReviewPage(const std::string& out, const GoldenRun& run) {
  CreateOutputFolder(out);
  // the heat map's own colours for 0..255 levels, so the scale cannot drift from the images
  std::vector<uint8_t> zero(256 * 3, 0), ramp(256 * 3);
  for (int i = 0; i < 256; ++i) ramp[i * 3] = ramp[i * 3 + 1] = ramp[i * 3 + 2] = i;
  const std::vector<uint8_t> scale = DiffHeatMap(zero.data(), ramp.data(), 256, 1);
  WritePng((fs::path(out) / "diff_scale.png").string(), 256, 1, 3, 8, scale.data());

  const bool check = run.command == "check";
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>fetchscope golden "
    << Escape(run.command) << "</title><style>" << kStyle << "</style></head><body>\n"
    << "<h1>fetchscope golden " << Escape(run.command) << "</h1>\n<p>" << Escape(run.manifest)
    << " on <code>" << Escape(run.running_on) << "</code>: " << Count(run, "pass") << " passed, "
    << Count(run, "fail") << " failed, " << Count(run, "error") << " could not be checked, "
    << Count(run, "skipped") << " skipped.</p>\n"
    << "<div class=\"scale\"><b>diff scale</b> (largest channel difference, levels; the box "
       "marks the pixels over the threshold)<img src=\"diff_scale.png\" alt=\"diff scale\">"
       "<div class=\"ticks\"><span>0</span><span>64</span><span>128</span><span>192</span>"
       "<span>255</span></div></div>\n";
  size_t shown = 0;
  for (const GoldenRow& r : run.rows) {
    const bool review = check ? r.status != "pass" : !r.verdict.empty() && r.verdict != "unchanged";
    if (!review || r.status == "skipped") continue;
    h << SceneSection(r);
    ++shown;
  }
  if (shown == 0)
    h << "<p id=\"nothing\">Nothing to review: every scene " << (check ? "passes" : "is unchanged")
      << ".</p>\n";
  h << "<h3>Other scenes</h3><ul id=\"others\">";
  for (const GoldenRow& r : run.rows) {
    const bool listed =
        check ? r.status == "pass" || r.status == "skipped"
              : r.verdict.empty() || r.verdict == "unchanged" || r.status == "skipped";
    if (listed) h << "<li>" << Escape(r.scene) << ": " << Escape(r.verdict) << "</li>";
  }
  h << "</ul></body></html>\n";
  const std::string page = (fs::path(out) / "index.html").string();
  WriteFileAtomically(page, h.str());
  return page;
}

}  // namespace fetchscope
