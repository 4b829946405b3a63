#include "inspect/golden.h"

#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "base/atomic_file.h"
#include "base/errors.h"
#include "base/json_util.h"
#include "base/stop_signal.h"
#include "encode/png_io.h"
#include "inspect/golden_scene.h"
#include "inspect/image_diff.h"
#include "render/gl_context.h"
#include "src/assets.h"

namespace fs = std::filesystem;

namespace fetchscope {
namespace {

/// What the state says when it differs, and when only the pixels do.
constexpr char kStateLayer[] = "state differs (physics or model)";
constexpr char kPixelLayer[] = "state equal, pixels differ (renderer or camera)";

bool HoldsAssets(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / "fetch" / "reach.xml", ec);
}

// The genuine assets folder, or empty (with `tried` saying where we looked) when absent.
std::string FindGenuineAssets(const GoldenOptions& o, std::string* tried) {
  if (!o.genuine_assets.empty()) {
    if (!HoldsAssets(o.genuine_assets)) {
      throw UsageError("--genuine-assets '" + o.genuine_assets +
                       "' has no fetch/reach.xml: give a Gymnasium-Robotics envs/assets folder");
    }
    return o.genuine_assets;
  }
  fs::path candidate;
  if (const char* shared = std::getenv("FETCHSCOPE_SHARED_DIR"); shared && *shared) {
    candidate = fs::path(shared) / "gymnasium-robotics-assets";
  } else {
    candidate = (fs::absolute(o.golden_dir) / ".." / ".." / "shared" / "gymnasium-robotics-assets")
                    .lexically_normal();
  }
  *tried = candidate.string();
  return HoldsAssets(candidate) ? candidate.string() : "";
}

// The selected scenes that can run here; genuine-asset scenes are dropped (with one line) when
// the genuine assets are absent.
std::vector<const GoldenScene*> RunnableScenes(const GoldenManifest& manifest,
                                               const GoldenOptions& o, std::string* genuine) {
  std::vector<const GoldenScene*> scenes = SelectScenes(manifest, o.only);
  std::string tried;
  *genuine = FindGenuineAssets(o, &tried);
  if (!genuine->empty()) return scenes;
  std::vector<const GoldenScene*> kept;
  std::string skipped;
  int n_skipped = 0;
  for (const GoldenScene* s : scenes) {
    if (s->assets == "genuine") {
      skipped += (skipped.empty() ? "" : ", ") + s->name;
      ++n_skipped;
    } else {
      kept.push_back(s);
    }
  }
  if (n_skipped > 0) {
    std::printf(
        "golden: skipping %d genuine-asset scene(s) (%s): no assets at '%s' "
        "(pass --genuine-assets DIR or set FETCHSCOPE_SHARED_DIR)\n",
        n_skipped, skipped.c_str(), tried.c_str());
  }
  return kept;
}

std::string GoldenPng(const GoldenManifest& m, const GoldenScene& s) {
  return (fs::path(m.dir) / (s.name + ".png")).string();
}

std::string GoldenState(const GoldenManifest& m, const GoldenScene& s) {
  return (fs::path(m.dir) / (s.name + "_state.json")).string();
}

// Reads a state golden; null when the file is missing.
nlohmann::json ReadState(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return nullptr;
  std::stringstream text;
  text << in.rdbuf();
  try {
    return nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::parse_error& e) {
    throw RunError("state golden '" + path + "' is not valid JSON: " + e.what());
  }
}

// Signals end the run after the scene in progress: the exit status 130 for SIGINT, 143 for
// SIGTERM; 0 when no signal came.
int Interrupted(const char* command, size_t done, size_t total) {
  const int sig = StopSignal();
  if (sig == 0) return 0;
  std::fprintf(stderr, "golden %s: interrupted by %s after %zu of %zu scenes\n", command,
               sig == SIGINT ? "SIGINT" : "SIGTERM", done, total);
  return 128 + sig;
}

/// One scene's outcome in `golden check`.
struct CheckRow {
  const GoldenScene* scene = nullptr;
  bool pass = false;
  bool state_equal = false;
  bool have_pixels = false;  // golden image read and of the same size
  ImageDiffStats stats;
  std::string verdict;  // "ok", or the layer that changed, or what is missing
  std::string detail;   // e.g. the first state difference
  double badness = 0;   // how far over its limits, for sorting worst first
};

void WriteFailureImages(const std::string& out, const GoldenScene& s, const Image* golden,
                        int width, int height, const std::vector<uint8_t>& actual) {
  CreateOutputFolder(out);
  const fs::path dir(out);
  WritePng((dir / (s.name + "_actual.png")).string(), width, height, 3, 8, actual.data());
  if (!golden) return;
  const std::vector<uint8_t> heat =
      DiffHeatMap(golden->pixels.data(), actual.data(), width, height);
  WritePng((dir / (s.name + "_diff.png")).string(), width, height, 3, 8, heat.data());
  const std::vector<uint8_t> side =
      SideBySide(golden->pixels.data(), actual.data(), heat.data(), width, height);
  WritePng((dir / (s.name + "_side.png")).string(), SideBySideWidth(width),
           SideBySideHeight(height), 3, 8, side.data());
}

CheckRow CheckScene(GlContext& gl, const GoldenManifest& m, const GoldenScene& s,
                    const std::string& genuine, const std::string& out) {
  CheckRow row;
  row.scene = &s;
  const SceneResult actual = RenderScene(gl, s, SceneAssets(s, m.dir, genuine));

  // the state first: it says whether the physics or model changed
  const nlohmann::json golden_state = ReadState(GoldenState(m, s));
  if (golden_state.is_null()) {
    row.verdict = "no state golden (run golden update)";
  } else {
    const StateComparison c = CompareStates(golden_state, actual.state, s.state_atol);
    row.state_equal = c.equal;
    if (!c.equal) {
      row.verdict = kStateLayer;
      row.detail = c.first;
    }
  }

  std::optional<Image> golden;
  const std::string png = GoldenPng(m, s);
  if (!fs::exists(png)) {
    if (row.verdict.empty()) row.verdict = "no golden image (run golden update)";
  } else {
    golden = ReadPng(png);
    if (golden->channels != 3 || golden->bit_depth != 8 || golden->width != actual.width ||
        golden->height != actual.height) {
      if (row.verdict.empty()) {
        row.verdict = "golden image is " + std::to_string(golden->width) + "x" +
                      std::to_string(golden->height) + " with " + std::to_string(golden->channels) +
                      " channels, the scene " + std::to_string(actual.width) + "x" +
                      std::to_string(actual.height) + " RGB (run golden update)";
      }
      golden.reset();
    } else {
      row.have_pixels = true;
      row.stats = CompareRgb(golden->pixels.data(), actual.rgb.data(), actual.width, actual.height,
                             s.tolerance.threshold);
      const double over = s.tolerance.max_fraction > 0
                              ? row.stats.fraction_over / s.tolerance.max_fraction
                              : (row.stats.pixels_over > 0 ? 1e9 : 0);
      const double rms = s.tolerance.max_rms > 0 ? row.stats.rms / s.tolerance.max_rms
                                                 : (row.stats.rms > 0 ? 1e9 : 0);
      row.badness = std::max(over, rms);
      const bool pixels_ok = row.stats.fraction_over <= s.tolerance.max_fraction &&
                             row.stats.rms <= s.tolerance.max_rms;
      if (!pixels_ok && row.verdict.empty()) row.verdict = kPixelLayer;
    }
  }
  row.pass = row.verdict.empty();
  if (row.pass) {
    row.verdict = "ok";
    return row;
  }
  if (!row.state_equal) row.badness += 1e6;  // a changed state outranks any pixel difference
  if (!row.have_pixels) row.badness += 1e9;  // nothing to compare at all: worst
  WriteFailureImages(out, s, golden ? &*golden : nullptr, actual.width, actual.height, actual.rgb);
  if (!row.state_equal && !golden_state.is_null()) {
    WriteJson((fs::path(out) / (s.name + "_state_actual.json")).string(), actual.state);
  }
  return row;
}

void PrintTable(const std::vector<CheckRow>& rows) {
  size_t name_width = 5;
  for (const CheckRow& r : rows) name_width = std::max(name_width, r.scene->name.size());
  // every column named: "result" is ok or FAIL
  std::printf("%-*s  %-6s  %9s %8s  %4s  %6s %6s  %s\n", static_cast<int>(name_width), "scene",
              "result", "over thr", "limit", "max", "rms", "limit", "verdict");
  for (const CheckRow& r : rows) {
    const GoldenTolerance& t = r.scene->tolerance;
    char over[32] = "-", max[16] = "-", rms[16] = "-";
    if (r.have_pixels) {
      std::snprintf(over, sizeof(over), "%.3f%%", 100 * r.stats.fraction_over);
      std::snprintf(max, sizeof(max), "%d", r.stats.max_diff);
      std::snprintf(rms, sizeof(rms), "%.3f", r.stats.rms);
    }
    std::printf("%-*s  %-6s  %9s %7.3f%%  %4s  %6s %6.3f  %s\n", static_cast<int>(name_width),
                r.scene->name.c_str(), r.pass ? "ok" : "FAIL", over, 100 * t.max_fraction, max, rms,
                t.max_rms, r.verdict.c_str());
  }
  for (const CheckRow& r : rows) {
    if (!r.detail.empty()) std::printf("  %s: %s\n", r.scene->name.c_str(), r.detail.c_str());
  }
}

}  // namespace

namespace {

// --golden-dir, or where it defaults to: ./golden, else for a check the goldens installed with
// the binary (so `golden check` runs from any folder); an update writes, so it never defaults to
// the installed copy (a rebuild or reinstall would replace what it wrote).
std::string ResolveGoldenDir(const std::string& given, bool writes) {
  if (!given.empty()) return given;
  std::error_code ec;
  if (fs::is_directory("golden", ec)) return "golden";
  const std::string installed = writes ? std::string() : InstalledDataDir("golden");
  if (!installed.empty()) return installed;
  throw UsageError(
      writes ? "golden update writes the goldens of a checkout: there is no ./golden here; run it "
               "from the checkout's root, or pass --golden-dir"
             : "no goldens: ./golden does not exist and none are installed beside the binary "
               "(<bin>/golden or <prefix>/share/fetchscope/golden); pass --golden-dir");
}

}  // namespace

int GoldenCheck(const GoldenOptions& options) {
  GoldenOptions o = options;
  o.golden_dir = ResolveGoldenDir(options.golden_dir, /*writes=*/false);
  const GoldenManifest manifest = ReadGoldenManifest(o.golden_dir);
  std::string genuine;
  const std::vector<const GoldenScene*> scenes = RunnableScenes(manifest, o, &genuine);
  if (scenes.empty()) {
    std::printf("golden check: no scene to check\n");
    return 0;
  }
  auto gl = CreateGlContext(o.backend, o.gpu);
  InstallStopSignals();  // finish the scene in progress, then stop
  std::vector<CheckRow> rows;
  for (const GoldenScene* s : scenes) {
    rows.push_back(CheckScene(*gl, manifest, *s, genuine, o.out));
    if (const int status = Interrupted("check", rows.size(), scenes.size())) return status;
  }
  std::stable_sort(rows.begin(), rows.end(), [](const CheckRow& a, const CheckRow& b) {
    if (a.pass != b.pass) return !a.pass;
    return a.badness > b.badness;
  });
  const GlInfo& gi = gl->info();
  const size_t failed =
      std::count_if(rows.begin(), rows.end(), [](const CheckRow& r) { return !r.pass; });
  std::printf(
      "golden check: %zu scene(s) from %s on %s via %s; a pixel counts as different when "
      "a channel differs by more than its threshold\n",
      rows.size(), (fs::path(manifest.dir) / "manifest.json").string().c_str(), gi.renderer.c_str(),
      gi.backend.c_str());
  PrintTable(rows);
  if (failed > 0) {
    std::printf(
        "golden check: %zu of %zu scene(s) FAILED; actual, diff and side-by-side images "
        "in %s\n",
        failed, rows.size(), o.out.c_str());
    return 1;
  }
  std::printf("golden check: all %zu scene(s) pass\n", rows.size());
  return 0;
}

int GoldenUpdate(const GoldenOptions& options) {
  GoldenOptions o = options;
  o.golden_dir = ResolveGoldenDir(options.golden_dir, /*writes=*/true);
  const GoldenManifest manifest = ReadGoldenManifest(o.golden_dir);
  std::string genuine;
  const std::vector<const GoldenScene*> scenes = RunnableScenes(manifest, o, &genuine);
  if (scenes.empty()) {
    std::printf("golden update: no scene to render\n");
    return 0;
  }
  auto gl = CreateGlContext(o.backend, o.gpu);
  InstallStopSignals();  // finish the scene in progress, then stop
  size_t done = 0;
  for (const GoldenScene* s : scenes) {
    const SceneResult actual = RenderScene(*gl, *s, SceneAssets(*s, manifest.dir, genuine));
    const std::string png = GoldenPng(manifest, *s);
    std::string change = "new";
    if (fs::exists(png)) {
      const Image old = ReadPng(png);
      if (old.channels == 3 && old.bit_depth == 8 && old.width == actual.width &&
          old.height == actual.height) {
        const ImageDiffStats d = CompareRgb(old.pixels.data(), actual.rgb.data(), actual.width,
                                            actual.height, s->tolerance.threshold);
        char buf[96];
        std::snprintf(buf, sizeof(buf), "max diff %d, %.3f%% over threshold, rms %.3f", d.max_diff,
                      100 * d.fraction_over, d.rms);
        change = d.max_diff == 0 ? "pixels unchanged" : buf;
      } else {
        change = "size changed";
      }
    }
    // each file appears whole or not at all (temporary name, then rename)
    WritePng(png, actual.width, actual.height, 3, 8, actual.rgb.data());
    WriteJson(GoldenState(manifest, *s), actual.state);
    std::printf("wrote %s and %s_state.json (%s)\n", png.c_str(), s->name.c_str(), change.c_str());
    std::fflush(stdout);  // progress shows in CI logs as it happens
    ++done;
    if (const int status = Interrupted("update", done, scenes.size())) return status;
  }
  const GlInfo& gi = gl->info();
  std::printf("golden update: %zu scene(s) rendered on %s via %s\n", done, gi.renderer.c_str(),
              gi.backend.c_str());
  return 0;
}

}  // namespace fetchscope
