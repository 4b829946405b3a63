#include "inspect/golden.h"

#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
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
#include "inspect/golden_meta.h"
#include "inspect/golden_report.h"
#include "inspect/golden_scene.h"
#include "inspect/image_diff.h"
#include "render/gl_context.h"
#include "src/assets.h"
#include "src/versions.h"

namespace fs = std::filesystem;

namespace fetchscope {
namespace {

/// What the state says when it differs, and when only the pixels do (and why, where it can tell).
constexpr char kStateLayer[] = "state differs (physics or model)";
constexpr char kPixelLayer[] = "state equal, pixels differ (renderer or camera)";
constexpr char kAppearance[] =
    "state equal, pixels differ (model appearance: materials, colours; segmentation unchanged)";
constexpr char kGeometry[] =
    "state equal, pixels differ (camera or model geometry: segmentation changed)";

// A failure to read or run what the check is given: the manifest, the assets, the GL. Exit 2.
[[noreturn]] void Unusable(const std::exception& e) { throw UsageError(e.what()); }

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
                                               const GoldenOptions& o, std::string* genuine,
                                               std::vector<std::string>* skipped_names = nullptr) {
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
      if (skipped_names) skipped_names->push_back(s->name);
    } else {
      kept.push_back(s);
    }
  }
  if (n_skipped > 0 && o.require_genuine) {
    throw UsageError("--require-genuine: " + std::to_string(n_skipped) +
                     " genuine-asset scene(s) (" + skipped + ") cannot run: no assets at '" +
                     tried + "'; pass --genuine-assets DIR or set FETCHSCOPE_SHARED_DIR");
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

std::string GoldenMetaPath(const GoldenManifest& m, const GoldenScene& s) {
  return (fs::path(m.dir) / (s.name + "_meta.json")).string();
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

// The golden image of a scene when it can be compared with a `width` x `height` RGB frame;
// otherwise nullopt, with `why` saying what is missing.
std::optional<Image> ReadGoldenImage(const std::string& png, int width, int height,
                                     std::string* why) {
  if (!fs::exists(png)) {
    *why = "no golden image (run golden update)";
    return std::nullopt;
  }
  Image golden = ReadPng(png);
  if (golden.channels != 3 || golden.bit_depth != 8 || golden.width != width ||
      golden.height != height) {
    *why = "golden image is " + std::to_string(golden.width) + "x" + std::to_string(golden.height) +
           " with " + std::to_string(golden.channels) + " channels, the scene " +
           std::to_string(width) + "x" + std::to_string(height) + " RGB (run golden update)";
    return std::nullopt;
  }
  return golden;
}

// The notes of a scene before any verdict: the assets changed (first: it explains the rest),
// metadata missing, versions, msaa capped now or then.
std::vector<std::string> MetaNotes(const GoldenScene& s, const nlohmann::json& meta,
                                   const SceneResult& actual) {
  std::vector<std::string> notes;
  if (s.msaa > 0 && actual.msaa_used != s.msaa) {
    notes.push_back("msaa " + std::to_string(s.msaa) + " asked, " +
                    std::to_string(actual.msaa_used) + " used: " + actual.msaa_reason);
  }
  if (meta.is_null()) {
    notes.push_back(
        "these goldens record no metadata (backend, GL renderer, versions, assets hash): the "
        "cross-backend tolerance applies; golden update records it");
    return notes;
  }
  const std::string then = meta.value("assets_sha256", "");
  if (!then.empty() && then != actual.assets_sha256) {
    notes.insert(notes.begin(), "the assets changed since these goldens were made (sha256 " +
                                    then.substr(0, 12) + "… then, " +
                                    actual.assets_sha256.substr(0, 12) + "… now)");
  }
  const nlohmann::json now = VersionsJson();
  if (meta.contains("versions") && meta["versions"] != now) {
    auto words = [](const nlohmann::json& v) {
      return "fetchscope " + v.value("fetchscope", std::string("?")) + ", MuJoCo " +
             v.value("mujoco", std::string("?"));
    };
    const nlohmann::json& then = meta["versions"];
    notes.push_back("goldens made with " + (then.is_object() ? words(then) : then.dump()) +
                    "; this is " + words(now));
  }
  if (meta.contains("msaa") && meta["msaa"].is_object() &&
      meta["msaa"].value("used", actual.msaa_used) != actual.msaa_used) {
    notes.push_back("msaa: the goldens used " + std::to_string(meta["msaa"].value("used", 0)) +
                    " samples, this check " + std::to_string(actual.msaa_used));
  }
  return notes;
}

// What changed when the state is equal and the pixels are not: the model's appearance when the
// objects each pixel shows are the same (a material or a colour), the camera or the geometry
// when they are not, on the renderer the goldens were made on; else the renderer or camera.
std::string PixelVerdict(const nlohmann::json& meta, const SceneResult& actual, bool same_backend) {
  const std::string then = meta.is_object() ? meta.value("segmentation_sha256", "") : "";
  if (then.empty()) return kPixelLayer;
  if (then == actual.segmentation_sha256) return kAppearance;
  if (same_backend) return kGeometry;
  return kPixelLayer;
}

// Compares the pixels of `actual` with `golden` under the row's tolerance (masks applied).
void ComparePixels(const GoldenScene& s, const Image& golden, const SceneResult& actual,
                   GoldenRow* row, std::vector<uint8_t>* masked) {
  *masked = actual.rgb;
  ApplyMasks(s.masks, golden.pixels.data(), masked->data(), actual.width, actual.height);
  row->have_pixels = true;
  const GoldenTolerance& t = row->tolerance;
  row->stats =
      CompareRgb(golden.pixels.data(), masked->data(), actual.width, actual.height, t.threshold);
  const double over = t.max_fraction > 0 ? row->stats.fraction_over / t.max_fraction
                                         : (row->stats.pixels_over > 0 ? 1e9 : 0);
  const double rms = t.max_rms > 0 ? row->stats.rms / t.max_rms : (row->stats.rms > 0 ? 1e9 : 0);
  row->badness = std::max(over, rms);
  row->region = FindChangedRegion(golden.pixels.data(), masked->data(), actual.width, actual.height,
                                  t.threshold);
}

bool PixelsPass(const GoldenRow& r) {
  return r.stats.fraction_over <= r.tolerance.max_fraction && r.stats.rms <= r.tolerance.max_rms;
}

void WriteImages(const std::string& out, const std::string& name, const Image* golden, int width,
                 int height, const std::vector<uint8_t>& actual, GoldenRow* row) {
  CreateOutputFolder(out);
  const fs::path dir(out);
  row->actual_png = name + "_actual.png";
  WritePng((dir / row->actual_png).string(), width, height, 3, 8, actual.data());
  if (!golden) return;
  row->golden_png = name + "_golden.png";
  WritePng((dir / row->golden_png).string(), width, height, 3, 8, golden->pixels.data());
  const std::vector<uint8_t> heat =
      DiffHeatMap(golden->pixels.data(), actual.data(), width, height);
  row->diff_png = name + "_diff.png";
  WritePng((dir / row->diff_png).string(), width, height, 3, 8, heat.data());
  const std::vector<uint8_t> side =
      SideBySide(golden->pixels.data(), actual.data(), heat.data(), width, height);
  row->side_png = name + "_side.png";
  WritePng((dir / row->side_png).string(), SideBySideWidth(width), SideBySideHeight(height), 3, 8,
           side.data());
}

// A scene that cannot be checked: its assets or XML do not load, a golden cannot be read, the
// GL fails, a mask lies outside the frame. Its row is an error; the check exits 2.
class SceneUnusable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What one scene is checked with: its render and its goldens.
struct SceneInputs {
  SceneResult actual;
  nlohmann::json meta;          // null: none recorded
  nlohmann::json golden_state;  // null: no state golden
  std::optional<Image> golden;  // nullopt: `missing` says why
  std::string missing;
};

SceneInputs LoadScene(GlContext& gl, const GoldenManifest& m, const GoldenScene& s,
                      const std::string& genuine) {
  try {
    SceneInputs in;
    in.actual = RenderScene(gl, s, SceneAssets(s, m.dir, genuine));
    const std::string bad = MaskOutsideFrame(s, in.actual.width, in.actual.height);
    if (!bad.empty()) throw UsageError("golden manifest '" + m.dir + "/manifest.json': " + bad);
    in.meta = ReadGoldenMeta(GoldenMetaPath(m, s));
    in.golden_state = ReadState(GoldenState(m, s));
    in.golden = ReadGoldenImage(GoldenPng(m, s), in.actual.width, in.actual.height, &in.missing);
    return in;
  } catch (const std::runtime_error& e) {
    throw SceneUnusable(e.what());
  }
}

// Checks one scene; SceneUnusable for one that cannot be checked.
GoldenRow CheckScene(GlContext& gl, const GoldenManifest& m, const GoldenScene& s,
                     const std::string& genuine, const GoldenOptions& o,
                     const ToleranceOverride& tolerance) {
  const SceneInputs in = LoadScene(gl, m, s, genuine);
  const SceneResult& actual = in.actual;
  const nlohmann::json& meta = in.meta;
  const nlohmann::json& golden_state = in.golden_state;
  const std::optional<Image>& golden = in.golden;
  GoldenRow row;
  row.scene = s.name;
  row.width = actual.width;
  row.height = actual.height;
  const ToleranceChoice choice = ChooseTolerance(s, meta, gl.info(), tolerance);
  row.tolerance = choice.tolerance;
  row.tolerance_why = choice.why;
  row.notes = MetaNotes(s, meta, actual);

  // the state first: it says whether the physics or model changed
  bool state_equal = false;
  if (golden_state.is_null()) {
    row.verdict = "no state golden (run golden update)";
  } else {
    const StateComparison c = CompareStates(golden_state, actual.state, s.state_atol);
    state_equal = c.equal;
    if (!c.equal) {
      row.verdict = kStateLayer;
      row.state_change =
          JoinDifferences(NamedStateDifferences(golden_state, actual.state, s.state_atol));
      row.notes.push_back("first difference: " + c.first);
    }
  }
  std::vector<uint8_t> masked = actual.rgb;
  if (!golden) {
    if (row.verdict.empty()) row.verdict = in.missing;
  } else {
    ComparePixels(s, *golden, actual, &row, &masked);
    if (!PixelsPass(row) && row.verdict.empty()) {
      row.verdict = PixelVerdict(meta, actual, choice.same_backend);
    }
  }
  if (row.verdict.empty()) {
    row.verdict = "ok";
    return row;
  }
  row.status = "fail";
  if (!state_equal) row.badness += 1e6;      // a changed state outranks any pixel difference
  if (!row.have_pixels) row.badness += 1e9;  // nothing to compare at all: worst
  WriteImages(o.out, s.name, golden ? &*golden : nullptr, actual.width, actual.height, masked,
              &row);
  if (!state_equal && !golden_state.is_null()) {
    WriteJson((fs::path(o.out) / (s.name + "_state_actual.json")).string(), actual.state);
  }
  return row;
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

namespace {

constexpr char kNoMeta[] = "these goldens record no metadata";

// The rows of the scenes, checked in order; `status` gets 128 + signal when interrupted.
std::vector<GoldenRow> CheckScenes(GlContext& gl, const GoldenManifest& manifest,
                                   const std::vector<const GoldenScene*>& scenes,
                                   const std::string& genuine, const GoldenOptions& o,
                                   int* status) {
  const ToleranceOverride tolerance = ParseToleranceOverride(o.tolerance);
  std::vector<GoldenRow> rows;
  for (const GoldenScene* s : scenes) {
    const auto start = std::chrono::steady_clock::now();
    try {
      rows.push_back(CheckScene(gl, manifest, *s, genuine, o, tolerance));
    } catch (const SceneUnusable& e) {  // its assets, XML or goldens cannot be used
      GoldenRow row;
      row.scene = s->name;
      row.status = "error";
      row.verdict = std::string("cannot be checked: ") + e.what();
      row.badness = 1e12;
      rows.push_back(row);
    }
    rows.back().seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if ((*status = Interrupted("check", rows.size(), scenes.size()))) break;
  }
  return rows;
}

// The lines printed before the table: changed assets first (they explain what follows), and
// once, goldens without metadata.
void PrintFirstNotes(const std::vector<GoldenRow>& rows) {
  size_t no_meta = 0;
  for (const GoldenRow& r : rows) {
    for (const std::string& n : r.notes) {
      if (n.rfind("the assets changed", 0) == 0) {
        std::printf("golden check: %s: %s\n", r.scene.c_str(), n.c_str());
      }
      no_meta += n.rfind(kNoMeta, 0) == 0;
    }
  }
  if (no_meta > 0) {
    std::printf(
        "golden check: %zu scene(s) have no NAME_meta.json (goldens written before fetchscope "
        "recorded the backend, GL renderer, versions and assets hash): their cross-backend "
        "tolerance applies; golden update records it\n",
        no_meta);
  }
}

// The review page when there is something to review (--out stays untouched when all pass), and
// the reports asked for.
void WriteReports(const GoldenOptions& o, const GoldenRun& run) {
  if (std::any_of(run.rows.begin(), run.rows.end(),
                  [](const GoldenRow& r) { return r.status == "fail" || r.status == "error"; })) {
    WriteGoldenReviewPage(o.out, run);
  }
  if (!o.junit.empty()) WriteGoldenJunit(o.junit, run);
  if (!o.json.empty()) WriteGoldenJson(o.json, run);
}

}  // namespace

namespace {

// A golden run's header: the command, its manifest, the GL it renders on, its --out.
GoldenRun StartRun(const char* command, const GoldenManifest& manifest, const GlContext& gl,
                   const GoldenOptions& o) {
  GoldenRun run;
  run.command = command;
  run.manifest = (fs::path(manifest.dir) / "manifest.json").string();
  run.running_on = RunningOn(gl.info());
  run.out = o.out;
  return run;
}

}  // namespace

int GoldenCheck(const GoldenOptions& options) {
  GoldenOptions o = options;
  o.golden_dir = ResolveGoldenDir(options.golden_dir, /*writes=*/false);
  ParseToleranceOverride(o.tolerance);  // a bad --tolerance before any rendering
  GoldenManifest manifest;
  try {
    manifest = ReadGoldenManifest(o.golden_dir);
  } catch (const RunError& e) {
    Unusable(e);
  }
  std::string genuine;
  std::vector<std::string> skipped;
  const std::vector<const GoldenScene*> scenes = RunnableScenes(manifest, o, &genuine, &skipped);
  if (scenes.empty()) {
    std::printf("golden check: no scene to check\n");
    return 0;
  }
  std::unique_ptr<GlContext> gl;
  try {
    gl = CreateGlContext(o.backend, o.gpu);
  } catch (const RunError& e) {
    Unusable(e);
  }
  InstallStopSignals();  // finish the scene in progress, then stop
  GoldenRun run = StartRun("check", manifest, *gl, o);
  int status = 0;
  run.rows = CheckScenes(*gl, manifest, scenes, genuine, o, &status);
  if (status != 0) return status;
  std::stable_sort(run.rows.begin(), run.rows.end(), [](const GoldenRow& a, const GoldenRow& b) {
    if ((a.status == "pass") != (b.status == "pass")) return b.status == "pass";
    return a.badness > b.badness;
  });
  for (const std::string& name : skipped) {
    GoldenRow row;
    row.scene = name;
    row.status = "skipped";
    row.verdict = "skipped: no genuine assets";
    run.rows.push_back(row);
  }
  auto count = [&](const char* st) {
    return std::count_if(run.rows.begin(), run.rows.end(),
                         [&](const GoldenRow& r) { return r.status == st; });
  };
  std::printf(
      "golden check: %zu scene(s) from %s on %s; a pixel counts as different when a channel "
      "differs by more than its threshold; tolerance on the goldens' own backend and GL renderer "
      "threshold %d, %.3f%%, rms %.1f (a few levels of colour fail), across backends the "
      "manifest's (measured: threshold 32, 0.2%%, rms 2)\n",
      scenes.size(), run.manifest.c_str(), run.running_on.c_str(), kSameBackendTolerance.threshold,
      100 * kSameBackendTolerance.max_fraction, kSameBackendTolerance.max_rms);
  PrintFirstNotes(run.rows);
  PrintGoldenTable(run.rows);
  WriteReports(o, run);
  const size_t failed = count("fail"), errors = count("error");
  if (failed + errors > 0) {
    std::printf(
        "golden check: %zu of %zu scene(s) FAILED, %zu could not be checked; review page %s/"
        "index.html (golden, actual, diff)\n",
        failed, scenes.size(), errors, o.out.c_str());
    return errors > 0 ? 2 : 1;
  }
  std::printf("golden check: all %zu scene(s) pass\n", scenes.size());
  return 0;
}

namespace {

// What an update changes in one scene, as a row of the review page: the old golden, the new
// image and their diff when the pixels changed, the state by named quantity.
GoldenRow UpdateRow(const GoldenManifest& m, const GoldenScene& s, const SceneResult& actual,
                    const std::string& out) {
  GoldenRow row;
  row.scene = s.name;
  row.width = actual.width;
  row.height = actual.height;
  row.tolerance = s.tolerance;
  row.tolerance_why = "the manifest's threshold, for the count";
  std::vector<std::string> changes;
  const nlohmann::json old_state = ReadState(GoldenState(m, s));
  if (!old_state.is_null()) {
    const std::string named =
        JoinDifferences(NamedStateDifferences(old_state, actual.state, s.state_atol, /*limit=*/5));
    const StateComparison c = CompareStates(old_state, actual.state, s.state_atol);
    if (!c.equal) {
      row.state_change = named.empty() ? c.first : named;
      changes.push_back("state: " + row.state_change);
    }
  }
  std::string missing;
  const std::optional<Image> old =
      ReadGoldenImage(GoldenPng(m, s), actual.width, actual.height, &missing);
  if (!old) {
    changes.push_back(fs::exists(GoldenPng(m, s)) ? "size changed" : "new");
  } else {
    row.have_pixels = true;
    row.stats = CompareRgb(old->pixels.data(), actual.rgb.data(), actual.width, actual.height,
                           s.tolerance.threshold);
    if (row.stats.max_diff > 0) {
      char buf[96];
      std::snprintf(buf, sizeof(buf), "pixels: max diff %d, %.3f%% over threshold, rms %.3f",
                    row.stats.max_diff, 100 * row.stats.fraction_over, row.stats.rms);
      changes.push_back(buf);
      row.region = FindChangedRegion(old->pixels.data(), actual.rgb.data(), actual.width,
                                     actual.height, s.tolerance.threshold);
    }
  }
  if (changes.empty()) {
    row.verdict = "unchanged";
    return row;
  }
  row.status = "fail";  // changed: listed for review
  for (const std::string& c : changes) row.verdict += (row.verdict.empty() ? "" : "; ") + c;
  WriteImages(out, s.name, old ? &*old : nullptr, actual.width, actual.height, actual.rgb, &row);
  return row;
}

}  // namespace

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
  GoldenRun run = StartRun("update", manifest, *gl, o);
  for (const GoldenScene* s : scenes) {
    const SceneResult actual = RenderScene(*gl, *s, SceneAssets(*s, manifest.dir, genuine));
    run.rows.push_back(UpdateRow(manifest, *s, actual, o.out));
    // each file appears whole or not at all (temporary name, then rename)
    const std::string png = GoldenPng(manifest, *s);
    WritePng(png, actual.width, actual.height, 3, 8, actual.rgb.data());
    WriteJson(GoldenState(manifest, *s), actual.state);
    WriteJson(GoldenMetaPath(manifest, *s), GoldenMetaJson(*s, actual, gl->info()));
    const std::string& change = run.rows.back().verdict;
    std::printf("wrote %s, %s_state.json and %s_meta.json (%s)\n", png.c_str(), s->name.c_str(),
                s->name.c_str(),
                change == "unchanged" ? "pixels unchanged, state unchanged" : change.c_str());
    std::fflush(stdout);  // progress shows in CI logs as it happens
    if (const int status = Interrupted("update", run.rows.size(), scenes.size())) return status;
  }
  const bool changed = std::any_of(run.rows.begin(), run.rows.end(),
                                   [](const GoldenRow& r) { return r.status == "fail"; });
  const std::string review =
      changed ? "review the changes before committing: " + WriteGoldenReviewPage(o.out, run)
              : "nothing changed";
  std::printf("golden update: %zu scene(s) rendered on %s; %s\n", run.rows.size(),
              run.running_on.c_str(), review.c_str());
  return 0;
}

}  // namespace fetchscope
