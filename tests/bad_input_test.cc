// The bad-input matrix: every subcommand fed unknown names, malformed numbers and specs, bad
// sizes, seeds Gymnasium rejects, broken assets and replay files, misbehaving exec policies and
// outputs that cannot be written. Each row runs the real binary and checks the promise to users:
// exit 2 (usage) or 1 (run time), a short message that names the bad value, no crash or abort
// text, and no file under a final output name (nor a leftover temporary). Also: mistyped flags
// and policies, and the anatomy commands' bad input.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "encode/png_io.h"
#include "encode/video_options.h"
#include "encode/video_writer.h"
#include "render/gl_context.h"
#include "render/renderer.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::GenuineAssetsDir;
using testing::RunCommand;
using testing::TempDir;
namespace fs = std::filesystem;
using testing::LinesWith;
using testing::RunFetchscope;

void WriteBytes(const fs::path& path, const std::string& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << bytes;
}

// A minimal NPY 1.0 file: header dict padded to 64 bytes, then raw data.
std::string Npy(const std::string& descr, const std::string& shape, const std::string& data) {
  std::string dict = "{'descr': '" + descr + "', 'fortran_order': False, 'shape': " + shape + ", }";
  const size_t unpadded = 10 + dict.size() + 1;
  dict += std::string((64 - unpadded % 64) % 64, ' ') + "\n";
  std::string out = "\x93NUMPY";
  out += '\x01';
  out += '\x00';
  out += static_cast<char>(dict.size() & 0xff);
  out += static_cast<char>(dict.size() >> 8);
  return out + dict + data;
}

std::string Doubles(const std::vector<double>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(double));
}

// `rows` CSV rows of 4 small actions.
std::string CsvRows(int rows) {
  std::string s;
  for (int i = 0; i < rows; ++i) s += "0.1,0.2,-0.3,0\n";
  return s;
}

// Copies the genuine assets to DIR/assets and breaks them with `edit`; false if they are absent.
bool CopyGenuineAssets(const fs::path& dir, const std::function<void(const fs::path&)>& edit) {
  const fs::path genuine = GenuineAssetsDir();
  if (genuine.empty()) return false;
  fs::copy(genuine, dir / "assets", fs::copy_options::recursive);
  edit(dir / "assets");
  return true;
}

// Prefix that runs the binary as an unprivileged user when we are root (root reads any file,
// so "unreadable" needs another user); empty otherwise.
std::string Unprivileged() {
  return geteuid() == 0 ? "setpriv --reuid=65534 --regid=65534 --clear-groups " : "";
}

struct Case {
  const char* name;    // test name suffix
  std::string args;    // after the binary; {tmp}: the case's temp folder, {src}: the sources
  int exit_code;       // 2 usage, 1 run time
  std::string needle;  // the message must name this (the bad value); {tmp} expanded
  std::vector<std::string> absent = {};             // final names under {tmp} that must not exist
  std::function<bool(const fs::path&)> setup = {};  // prepares {tmp}; false: skip (no assets)
  std::string prefix = {};     // shell text before the binary (ulimit, setpriv)
  const char* skip = nullptr;  // non-null: a known bug in another engineer's file, see reason
};

std::string Expand(std::string s, const fs::path& tmp) {
  const std::pair<std::string, std::string> vars[] = {{"{tmp}", tmp.string()},
                                                      {"{src}", testing::SourceDir().string()}};
  for (const auto& [key, value] : vars) {
    for (size_t p = s.find(key); p != std::string::npos; p = s.find(key, p + value.size())) {
      s.replace(p, key.size(), value);
    }
  }
  return s;
}

// Files a record run would write for episode 0.
const std::vector<std::string> kRecordOutputs = {
    "out/episode_000.mp4",  "out/episode_000.webm",
    "out/episode_000.gif",  "out/episode_000_sheet.png",
    "out/episode_000.json", "out/manifest.json",
    "out/index.html"};

// A minimal record manifest for `report` and `compare` rows.
std::string Manifest(const std::string& env, const std::string& episodes) {
  return R"({"env_id": ")" + env + R"(", "seed": 0, "steps_per_episode": 3, "episodes_requested": 1,
             "episodes": )" +
         episodes + "}";
}

const char kSmall[] = " --width 64 --height 48 --steps 3 ";
const char kUlimit[] = "trap '' XFSZ; ulimit -f 16; ";  // 8 KiB: SIGXFSZ ignored -> EFBIG

std::vector<Case> Matrix() {
  auto file = [](const std::string& rel, std::string bytes) {
    return [rel, bytes](const fs::path& tmp) {
      WriteBytes(tmp / rel, bytes);
      return true;
    };
  };
  auto unreadable = [](const std::string& rel) {
    return [rel](const fs::path& tmp) {
      WriteBytes(tmp / rel, CsvRows(60));
      fs::permissions(tmp / rel, fs::perms::none);
      fs::permissions(tmp, fs::perms::all);  // the unprivileged user may enter and write
      return true;
    };
  };
  auto assets = [](std::function<void(const fs::path&)> edit) {
    return [edit](const fs::path& tmp) { return CopyGenuineAssets(tmp, edit); };
  };
  auto truncate = [](const fs::path& p, size_t keep) {
    std::string s = testing::ReadFile(p);
    std::ofstream(p, std::ios::binary | std::ios::trunc) << s.substr(0, keep);
  };
  const std::string rollout = "rollout --env-id FetchReach-v4 --steps 50 --json-out {tmp}/r.json ";
  const std::vector<std::string> rollout_out = {"r.json"};
  const std::string record_long =
      "record --env-id FetchReach-v4 --quiet --width 64 --height 48 "
      "--steps 10 --out {tmp}/out ";
  const std::string record =
      std::string("record --env-id FetchReach-v4 --quiet") + kSmall + "--out {tmp}/out ";
  return {
      // ---- unknown subcommands, ids and names
      {"UnknownSubcommand", "frobnicate", 2, "frobnicate"},
      {"NoSubcommand", "", 2, "subcommand"},
      {"UnknownOption", "list-envs --colour", 2, "--colour"},
      {"DescribeUnknownEnv", "describe --env-id FetchFoo-v4", 2, "FetchFoo-v4"},
      {"RolloutOldEnvVersion", "rollout --env-id FetchReach-v1", 2, "FetchReach-v1"},
      {"RewardCheckEmptyEnv", "reward-check --env-id ''", 2, "env"},
      {"ListCamerasUnknownEnv", "list-cameras --env-id HandReach-v1", 2, "HandReach-v1"},
      {"RolloutUnknownPolicy", "rollout --policy bogus", 2, "bogus"},
      // ---- misspelt names get the nearest accepted one
      {"MisspeltCommand", "reward-chek", 2, "did you mean 'reward-check'?"},
      {"DescribeMisspeltEnv", "describe --env-id FetchRech-v4", 2,
       "'FetchRech-v4' (did you mean 'FetchReach-v4'?)"},
      {"RenderMisspeltCamera",
       "render --camera 'default, trak' -o {tmp}/f.png",
       2,
       "'trak' is not known (did you mean 'track'?)",
       {"f.png"}},
      {"RenderMisspeltModelCamera",
       "render --camera head_camera_rbg -o {tmp}/f.png",
       2,
       "did you mean 'head_camera_rgb'?",
       {"f.png"}},
      {"RenderMisspeltOverlay",
       "render --overlay 'goal, hdu' -o {tmp}/f.png",
       2,
       "'hdu' in 'goal, hdu' is not known (did you mean 'hud'?)",
       {"f.png"}},
      {"RenderMisspeltLayer",
       "render --layers 'rgb, dpeth' -o {tmp}/f.png",
       2,
       "'dpeth' (did you mean 'depth'?)",
       {"f.png"}},
      {"RenderEmptyOverlayItem",
       "render --overlay 'goal, ' -o {tmp}/f.png",
       2,
       "overlay ''",
       {"f.png"}},
      // ---- anatomy: bad input is refused before any file or folder appears
      {"AnatomyUnknownEnv",
       "anatomy --env-id FetchFoo-v4 --out {tmp}/results",
       2,
       "FetchFoo-v4",
       {"results"}},
      {"AnatomyBadSeed", "anatomy --seed -1 --out {tmp}/results", 2, "-1", {"results"}},
      {"AnatomyBadMsaa", "anatomy --msaa 3 --out {tmp}/results", 2, "3", {"results"}},
      {"AnatomyTinyCard", "anatomy --width 10 --out {tmp}/results", 2, "10", {"results"}},
      {"AnatomyOutIsFile", "anatomy --no-card --out {tmp}/f", 2, "{tmp}/f", {}, file("f", "x")},
      {"RolloutEmptyExec", "rollout --policy exec:", 2, "exec"},
      {"RolloutEmptyReplay", "rollout --policy replay:", 2, "replay"},
      {"RenderUnknownBackend", "render --backend vulkan -o {tmp}/f.png", 2, "vulkan", {"f.png"}},
      {"RenderUnknownCamera",
       "render --camera nosuchcam -o {tmp}/f.png",
       2,
       "nosuchcam",
       {"f.png"}},
      {"RenderFreeCameraBadNumber",
       "render --camera free:distance=abc -o {tmp}/f.png",
       2,
       "abc",
       {"f.png"}},
      {"RenderFreeCameraUnknownKey",
       "render --camera free:zoom=3 -o {tmp}/f.png",
       2,
       "zoom",
       {"f.png"}},
      {"RenderFreeCameraShortLookat",
       "render --camera free:lookat=1,2 -o {tmp}/f.png",
       2,
       "lookat",
       {"f.png"}},
      {"RenderFreeCameraNaN",
       "render --camera free:distance=nan -o {tmp}/f.png",
       2,
       "nan",
       {"f.png"}},
      {"RenderEmptyCamera", "render --camera '' -o {tmp}/f.png", 2, "camera", {"f.png"}},
      {"RenderUnknownOverlay",
       "render --overlay sparkles -o {tmp}/f.png",
       2,
       "sparkles",
       {"f.png"}},
      {"RenderUnknownLayer", "render --layers rgb,heat -o {tmp}/f.png", 2, "heat", {"f.png"}},
      {"RenderBadMsaa", "render --msaa 3 -o {tmp}/f.png", 2, "3", {"f.png"}},
      {"RenderNoOutput", "render", 2, "--output"},
      {"RecordUnknownCodec", record + "--codec prores", 2, "prores", kRecordOutputs},
      {"RecordUnknownPreset", record + "--preset warp9", 2, "warp9", kRecordOutputs},
      {"RecordUnknownFormat", record + "--format mp4,avi", 2, "'avi'", kRecordOutputs},
      {"RecordEmptyFormat", record + "--format mp4,", 2, "--format", kRecordOutputs},
      {"RecordRepeatedFormat", record + "--format gif,gif", 2, "gif twice", kRecordOutputs},
      {"RecordGifFpsZero", record + "--format gif --gif-fps 0", 2, "GIF fps 0", kRecordOutputs},
      {"RecordGifFpsTooHigh", record + "--format gif --gif-fps 99", 2, "GIF fps 99",
       kRecordOutputs},
      {"RecordGifFpsText", record + "--format gif --gif-fps ten", 2, "ten", kRecordOutputs},
      {"RecordGifWidthTooSmall", record + "--format gif --gif-width 4", 2, "GIF width 4",
       kRecordOutputs},
      {"RecordFontMissing",
       record,
       1,
       "FETCHSCOPE_FONT='/nonexistent/fetchscope-font.ttf'",
       kRecordOutputs,
       {},
       "FETCHSCOPE_FONT=/nonexistent/fetchscope-font.ttf "},
      {"RecordGifWidthTooLarge", record + "--format webm --gif-width 9000", 2, "GIF width 9000",
       kRecordOutputs},
      {"GoldenUnknownSubcommand", "golden frob", 2, "frob"},
      {"GoldenMissingFolder", "golden check --golden-dir {tmp}/nowhere --out {tmp}/g", 2,
       "{tmp}/nowhere"},
      {"GoldenUpdateMissingFolder", "golden update --golden-dir {tmp}/nowhere", 2, "{tmp}/nowhere"},
      {"GoldenUnknownScene",
       "golden check --golden-dir {src}/golden --only nosuchscene --out {tmp}/g", 2, "nosuchscene"},
      {"GoldenMalformedManifest",
       "golden check --golden-dir {tmp}/gd --out {tmp}/g",
       2,
       "manifest.json",
       {"g"},
       file("gd/manifest.json", "{\"scenes\": [")},
      {"MergeNoFolder", "merge-manifests", 2, "DIR"},
      // ---- report and compare
      {"ReportNoFolder", "report", 2, "DIR"},
      {"ReportMissingFolder", "report {tmp}/nowhere", 2, "{tmp}/nowhere", {"nowhere/index.html"}},
      {"ReportNoManifest", "report {tmp}", 2, "manifest.json", {"index.html"}},
      {"ReportShardManifestsOnly",
       "report {tmp}/m",
       2,
       "merge-manifests",
       {"m/index.html"},
       file("m/manifest_shard_0000_of_0002.json", "{}")},
      {"ReportManifestNotJson",
       "report {tmp}/m",
       2,
       "not JSON",
       {"m/index.html"},
       file("m/manifest.json", "{\"env_id\": ")},
      {"ReportManifestNotARecordManifest",
       "report {tmp}/m",
       2,
       "not a record manifest",
       {"m/index.html"},
       file("m/manifest.json", "[1, 2, 3]")},
      {"CompareNoOut", "compare {tmp}/a {tmp}/b", 2, "--out"},
      {"CompareMissingRun",
       "compare {tmp}/a {tmp}/b --out {tmp}/c",
       2,
       "{tmp}/a",
       {"c/index.html", "c/compare.json"}},
      {"CompareNegativeTolerance",
       "compare {tmp}/a {tmp}/b --out {tmp}/c --tolerance -1",
       2,
       "-1",
       {"c/index.html", "c/compare.json"}},
      {"ComparePixelToleranceOutOfRange",
       "compare {tmp}/a {tmp}/b --out {tmp}/c --pixel-tolerance 300",
       2,
       "300",
       {"c/index.html", "c/compare.json"}},
      {"CompareDifferentEnvs",
       "compare {tmp}/a {tmp}/b --out {tmp}/c",
       2,
       "FetchPush-v4",
       {"c/index.html", "c/compare.json"},
       [](const fs::path& tmp) {
         WriteBytes(tmp / "a/manifest.json", Manifest("FetchReach-v4", R"([{"index": 0}])"));
         WriteBytes(tmp / "b/manifest.json", Manifest("FetchPush-v4", R"([{"index": 0}])"));
         return true;
       }},
      {"CompareDifferentEpisodes",
       "compare {tmp}/a {tmp}/b --out {tmp}/c",
       2,
       "different episodes",
       {"c/index.html", "c/compare.json"},
       [](const fs::path& tmp) {
         WriteBytes(tmp / "a/manifest.json", Manifest("FetchReach-v4", R"([{"index": 0}])"));
         WriteBytes(tmp / "b/manifest.json", Manifest("FetchReach-v4", R"([{"index": 1}])"));
         return true;
       }},
      {"CompareMissingTrajectory",
       "compare {tmp}/a {tmp}/b --out {tmp}/c",
       2,
       "episode_000.json",
       {"c/index.html", "c/compare.json", "c/compare_episode_000.mp4"},
       [](const fs::path& tmp) {
         const std::string entry =
             R"([{"index": 0, "trajectory": "episode_000.json", "video": "episode_000.mp4"}])";
         WriteBytes(tmp / "a/manifest.json", Manifest("FetchReach-v4", entry));
         WriteBytes(tmp / "b/manifest.json", Manifest("FetchReach-v4", entry));
         return true;
       }},
      {"MergeMissingFolder",
       "merge-manifests {tmp}/nowhere",
       1,
       "{tmp}/nowhere",
       {"nowhere/manifest.json"}},
      {"MergeMalformedShard",
       "merge-manifests {tmp}/m",
       1,
       "manifest_shard_0_of_2.json",
       {"m/manifest.json"},
       file("m/manifest_shard_0_of_2.json", "{not json")},
      {"RecordShardOutOfRange", record + "--shard 3/2", 2, "3/2", kRecordOutputs},
      {"RecordHudPositionUnknown", record + "--hud-position middle", 2, "middle", kRecordOutputs},
      {"RecordHudOpacityTooHigh", record + "--hud-opacity 1.5", 2, "1.5", kRecordOutputs},
      {"RenderHudPositionUnknown",
       "render --hud-position centre -o {tmp}/f.png",
       2,
       "centre",
       {"f.png"}},
      {"RecordUnknownOverlayHindsightListed", record + "--overlay hindsigth", 2, "hindsight",
       kRecordOutputs},
      {"RecordFromMissing", "record --quiet --out {tmp}/out --from {tmp}/nothing", 2,
       "{tmp}/nothing", kRecordOutputs},
      {"RecordFromNotJson", "record --quiet --out {tmp}/out --from {tmp}/t.json", 1, "t.json",
       kRecordOutputs, file("t.json", "not json")},
      {"RecordFromNotATrajectory", "record --quiet --out {tmp}/out --from {tmp}/t.json", 1,
       "not a fetchscope trajectory", kRecordOutputs, file("t.json", "{\"a\": 1}")},
      {"RecordFromEmptyFolder", "record --quiet --out {tmp}/out --from {tmp}", 2,
       "no episode_NNN.json", kRecordOutputs},
      {"RecordFromWithSeed", "record --quiet --out {tmp}/out --seed 3 --from {tmp}/t.json", 2,
       "--seed cannot be used with --from", kRecordOutputs},
      {"RecordFromWithReplayDtype",  // a recording's actions replay as recorded
       "record --quiet --out {tmp}/out --replay-dtype float32 --from {tmp}/t.json", 2,
       "--replay-dtype applies to --policy replay:FILE only", kRecordOutputs,
       [](const fs::path& tmp) {
         return testing::RunFetchscope("rollout --env-id FetchReach-v4 --steps 2 --json-out " +
                                       (tmp / "t.json").string())
                    .exit_code == 0;
       }},
      {"RecordShardMalformed", record + "--shard half", 2, "half", kRecordOutputs},
      {"RecordShardZeroShards", record + "--shard 0/0", 2, "0/0", kRecordOutputs},
      {"RecordJobsNegative", record + "--jobs -1", 2, "-1", kRecordOutputs},
      {"BenchUnknownWhat", "bench --what everything --no-peers", 2, "everything"},
      {"BenchUnknownBackend",
       "bench --what render --backends vulkan --no-peers --seconds 0.1",
       2,
       "vulkan",
       {},
       {},
       {}},
      // ---- malformed numbers, zero / negative / huge sizes and counts
      {"WidthZero", "render --width 0 -o {tmp}/f.png", 2, "0", {"f.png"}},
      {"WidthNegative", "render --width -5 -o {tmp}/f.png", 2, "-5", {"f.png"}},
      {"WidthHuge", "render --width 100000 -o {tmp}/f.png", 2, "100000", {"f.png"}},
      {"WidthOverflow",
       "render --width 99999999999999999999 -o {tmp}/f.png",
       2,
       "99999999999999999999",
       {"f.png"}},
      {"WidthNotANumber", "render --width wide -o {tmp}/f.png", 2, "wide", {"f.png"}},
      {"WidthFraction", "render --width 64.5 -o {tmp}/f.png", 2, "64.5", {"f.png"}},
      {"HeightZero", record + "--height 0", 2, "0", kRecordOutputs},
      {"RecordEpisodesZero", record + "--episodes 0", 2, "0", kRecordOutputs},
      {"RecordEpisodesNegative", record + "--episodes -2", 2, "-2", kRecordOutputs},
      {"RecordEpisodesHuge", record + "--episodes 99999999999", 2, "99999999999", kRecordOutputs},
      {"RecordStepsZero", "record --steps 0 --out {tmp}/out", 2, "0", kRecordOutputs},
      {"RecordStepsOverMax", "record --steps 10001 --out {tmp}/out", 2, "10001", kRecordOutputs},
      {"RecordFpsZero", record + "--fps 0", 2, "fps", kRecordOutputs},
      {"RecordFpsNegative", record + "--fps -25", 2, "-25", kRecordOutputs},
      {"RecordCrfOutOfRange", record + "--crf 99", 2, "99", kRecordOutputs},
      {"RecordSheetEveryNegative", record + "--sheet-every -1", 2, "-1", kRecordOutputs},
      {"RolloutEpisodesText", "rollout --episodes many", 2, "many"},
      {"RolloutStepsNegative", "rollout --steps -1", 2, "-1"},
      {"RandomEpisodesZero", "random-episodes --n-episodes 0", 2, "0"},
      {"RandomEpisodesNegative", "random-episodes --n-episodes -3", 2, "-3"},
      {"RewardCheckStepsZero", "reward-check --n-steps 0", 2, "0"},
      {"ProbeStepsZero", "probe-actions --steps 0", 2, "0"},
      {"ProbeMagnitudesText", "probe-actions --magnitudes 0.5,big", 2, "big"},
      {"ProbeMagnitudesEmptyItem", "probe-actions --magnitudes 0.5,,1", 2, "magnitudes"},
      {"ProbeMagnitudesNaN", "probe-actions --magnitudes nan", 2, "nan"},
      {"BenchSecondsZero", "bench --seconds 0 --no-peers", 2, "0"},
      {"ExecTimeoutZero", "rollout --policy exec:cat --exec-timeout 0", 2, "0"},
      {"ExecTimeoutNegative", "rollout --policy exec:cat --exec-timeout -1", 2, "-1"},
      {"GpuNegativeEgl", "render --backend egl --gpu -7 -o {tmp}/f.png", 2, "-7", {"f.png"}},
      // ---- seeds outside what Gymnasium accepts (a non-negative integer)
      {"SeedNegative", "rollout --seed -1", 2, "-1"},
      {"SeedFraction", "rollout --seed 1.5", 2, "1.5"},
      {"SeedText", "describe --seed abc", 2, "abc"},
      {"SeedEmpty", "rollout --seed ''", 2, "seed"},
      {"SeedHex", "rollout --seed 0x10", 2, "0x10"},
      {"SeedPlusSign", "rollout --seed +5", 2, "+5"},
      {"SeedTooLarge", "rollout --seed 18446744073709551616", 2, "18446744073709551616"},
      {"SeedRecordNegative", record + "--seed -3", 2, "-3", kRecordOutputs},
      // ---- missing, unreadable and malformed assets
      {"AssetsMissingFolder", "describe --assets {tmp}/nowhere", 2, "{tmp}/nowhere"},
      {"AssetsIsAFile", "rollout --assets {tmp}/a.txt", 2, "{tmp}/a.txt", {}, file("a.txt", "x")},
      {"AssetsEmptyFolder",
       "rollout --assets {tmp}/empty",
       2,
       "{tmp}/empty",
       {},
       [](const fs::path& tmp) { return fs::create_directory(tmp / "empty"); }},
      {"AssetsTruncatedXml",
       "rollout --env-id FetchReach-v4 --assets {tmp}/assets",
       1,
       "reach.xml",
       {},
       assets([&](const fs::path& a) { truncate(a / "fetch" / "reach.xml", 300); })},
      // MuJoCo's include error names the including model and line, not shared.xml itself
      {"AssetsTruncatedSharedXml",
       "rollout --env-id FetchPush-v4 --assets {tmp}/assets",
       1,
       "push.xml",
       {},
       assets([&](const fs::path& a) { truncate(a / "fetch" / "shared.xml", 500); })},
      {"AssetsMissingMesh",
       "rollout --env-id FetchReach-v4 --assets {tmp}/assets",
       1,
       "gripper_link.stl",
       {},
       assets([](const fs::path& a) { fs::remove(a / "stls" / "fetch" / "gripper_link.stl"); })},
      {"AssetsTruncatedMesh",
       "rollout --env-id FetchReach-v4 --assets {tmp}/assets",
       1,
       "gripper_link.stl",
       {},
       assets(
           [&](const fs::path& a) { truncate(a / "stls" / "fetch" / "gripper_link.stl", 100); })},
      // MuJoCo names the texture, not its file
      {"AssetsMissingTexture",
       "rollout --env-id FetchPush-v4 --assets {tmp}/assets",
       1,
       "texture_block",
       {},
       assets([](const fs::path& a) { fs::remove(a / "textures" / "block.png"); })},
      {"AssetsCorruptTexture",
       "rollout --env-id FetchPush-v4 --assets {tmp}/assets",
       1,
       "texture_block",
       {},
       assets([&](const fs::path& a) { truncate(a / "textures" / "block.png", 40); })},
      {"AssetsBrokenRecord", record + "--assets {tmp}/assets", 1, "gripper_link.stl",
       kRecordOutputs,
       assets([](const fs::path& a) { fs::remove(a / "stls" / "fetch" / "gripper_link.stl"); })},
      // ---- replay files: empty, binary, wrong width or shape, NaN/inf, too few rows
      {"ReplayMissingFile", rollout + "--policy replay:{tmp}/none.csv", 2, "{tmp}/none.csv",
       rollout_out},
      {"ReplayUnknownExtension", rollout + "--policy replay:{tmp}/a.txt", 2, ".txt", rollout_out,
       file("a.txt", CsvRows(60))},
      {"ReplayIsAFolder", rollout + "--policy replay:{tmp}/d.csv", 2, "{tmp}/d.csv", rollout_out,
       [](const fs::path& tmp) { return fs::create_directory(tmp / "d.csv"); }},
      {"ReplayUnreadable", rollout + "--policy replay:{tmp}/u.csv", 2, "{tmp}/u.csv", rollout_out,
       unreadable("u.csv"), Unprivileged()},
      {"ReplayEmptyCsv", rollout + "--policy replay:{tmp}/e.csv", 1, "e.csv", rollout_out,
       file("e.csv", "")},
      {"ReplayEmptyNpy", rollout + "--policy replay:{tmp}/e.npy", 1, "e.npy", rollout_out,
       file("e.npy", "")},
      {"ReplayEmptyJsonl", rollout + "--policy replay:{tmp}/e.jsonl", 1, "e.jsonl", rollout_out,
       file("e.jsonl", "")},
      {"ReplayBinaryCsv", rollout + "--policy replay:{tmp}/b.csv", 1, "b.csv", rollout_out,
       file("b.csv", std::string("\x7f"
                                 "ELF\x02\x01\x01\0\0\0\xff\xfe,\x80\n",
                                 16))},
      {"ReplayBinaryJsonl", rollout + "--policy replay:{tmp}/b.jsonl", 1, "b.jsonl", rollout_out,
       file("b.jsonl", std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16))},
      {"ReplayNotNpy", rollout + "--policy replay:{tmp}/b.npy", 1, "b.npy", rollout_out,
       file("b.npy", CsvRows(60))},
      {"ReplayCsvThreeColumns", rollout + "--policy replay:{tmp}/w.csv", 1, "w.csv", rollout_out,
       file("w.csv", "0.1,0.2,0.3\n0.1,0.2,0.3\n")},
      {"ReplayCsvFiveColumns", rollout + "--policy replay:{tmp}/w.csv", 1, "w.csv", rollout_out,
       file("w.csv", "0.1,0.2,0.3,0.4,0.5\n")},
      {"ReplayNpyWrongWidth", rollout + "--policy replay:{tmp}/w.npy", 1, "w.npy", rollout_out,
       file("w.npy", Npy("<f8", "(2, 3)", Doubles({0, 0, 0, 0, 0, 0})))},
      {"ReplayNpyOneDimension", rollout + "--policy replay:{tmp}/w.npy", 1, "w.npy", rollout_out,
       file("w.npy", Npy("<f8", "(4,)", Doubles({0, 0, 0, 0})))},
      {"ReplayNpyIntegers", rollout + "--policy replay:{tmp}/i.npy", 1, "<i4", rollout_out,
       file("i.npy", Npy("<i4", "(1, 4)", std::string(16, '\0')))},
      {"ReplayNpyTruncatedData", rollout + "--policy replay:{tmp}/t.npy", 1, "t.npy", rollout_out,
       file("t.npy", Npy("<f8", "(60, 4)", Doubles({0, 0, 0, 0})))},
      {"ReplayNpyHugeShape", rollout + "--policy replay:{tmp}/h.npy", 1, "h.npy", rollout_out,
       file("h.npy", Npy("<f8", "(4611686018427387904, 4)", Doubles({0, 0, 0, 0})))},
      {"ReplayJsonlWrongWidth", rollout + "--policy replay:{tmp}/w.jsonl", 1, "w.jsonl",
       rollout_out, file("w.jsonl", "[0.1, 0.2]\n")},
      {"ReplayJsonlNotArray", rollout + "--policy replay:{tmp}/w.jsonl", 1, "w.jsonl", rollout_out,
       file("w.jsonl", "{\"dx\": 1}\n")},
      {"ReplayCsvNaN", rollout + "--policy replay:{tmp}/n.csv", 1, "n.csv", rollout_out,
       file("n.csv", "0,0,0,0\nnan,0,0,0\n")},
      {"ReplayCsvInf", rollout + "--policy replay:{tmp}/n.csv", 1, "n.csv", rollout_out,
       file("n.csv", "0,inf,0,0\n")},
      {"ReplayCsvOverflow", rollout + "--policy replay:{tmp}/n.csv", 1, "n.csv", rollout_out,
       file("n.csv", "0,1e999,0,0\n")},
      {"ReplayNpyNaN", rollout + "--policy replay:{tmp}/n.npy", 1, "n.npy", rollout_out,
       file("n.npy", Npy("<f8", "(1, 4)", Doubles({0, 0, std::nan(""), 0})))},
      {"ReplayNpyInf", rollout + "--policy replay:{tmp}/n.npy", 1, "n.npy", rollout_out,
       file("n.npy", Npy("<f8", "(1, 4)", Doubles({0, -HUGE_VAL, 0, 0})))},
      {"ReplayJsonlNaN", rollout + "--policy replay:{tmp}/n.jsonl", 1, "n.jsonl", rollout_out,
       file("n.jsonl", "[NaN, 0, 0, 0]\n")},
      {"ReplayTooFewRowsCsv", rollout + "--policy replay:{tmp}/few.csv", 1, "10", rollout_out,
       file("few.csv", CsvRows(10))},
      {"ReplayTooFewRowsTwoEpisodes", rollout + "--episodes 2 --policy replay:{tmp}/few.csv", 1,
       "60", rollout_out, file("few.csv", CsvRows(60))},
      {"ReplayTooFewRowsRecord", record + "--policy replay:{tmp}/few.csv", 1, "2", kRecordOutputs,
       file("few.csv", CsvRows(2))},
      // ---- exec policies that exit, hang or answer garbage
      {"ExecExitsAtOnce", rollout + "--policy exec:true", 1, "exited", rollout_out},
      {"ExecExitsWithStatus", rollout + "--policy \"exec:read l; exit 3\"", 1, "status 3",
       rollout_out},
      {"ExecCommandNotFound", rollout + "--policy exec:/nonexistent/policy", 1, "127", rollout_out},
      {"ExecHangs", rollout + "--exec-timeout 0.3 --policy \"exec:sleep 30\"", 1, "0.3",
       rollout_out},
      {"ExecGarbage", rollout + "--policy \"exec:yes garbage\"", 1, "garbage", rollout_out},
      {"ExecPrintsALogLine", rollout + "--policy \"exec:read l; echo loading model; yes 0 0 0 0\"",
       1, "'loading model' is not 4 numbers", rollout_out},
      {"ExecLogLineSaysStderr", rollout + "--policy \"exec:echo hello; yes 0 0 0 0\"", 1,
       "send logs and prints to stderr", rollout_out},
      {"ExecThreeNumbers", rollout + "--policy \"exec:yes 1 2 3\"", 1, "1 2 3", rollout_out},
      {"ExecNaN", rollout + "--policy \"exec:yes nan 0 0 0\"", 1, "nan", rollout_out},
      {"ExecBadJson", rollout + "--policy \"exec:yes '[1, 2, 3,'\"", 1, "[1, 2, 3,", rollout_out},
      {"ExecEndlessLine",
       rollout + "--policy \"exec:tr -d '\\n' </dev/zero 2>/dev/null | tr '\\0' 1 2>/dev/null\"", 1,
       "64 KiB", rollout_out},
      {"ExecDiesMidEpisode",
       record_long + "--policy \"exec:for i in 1 2 3 4 5; do read l; echo 0 0 0 0; done\"", 1,
       "step 5", kRecordOutputs},
      {"ExecHangsInRecord", record_long + "--exec-timeout 0.3 --policy \"exec:sleep 30\"", 1, "0.3",
       kRecordOutputs},
      // an answer that never gets its newline: said as such, not as silence (the child sleeps
      // on; the timeout ends the wait)
      {"ExecAnswerWithoutNewline",
       rollout + "--exec-timeout 0.5 --policy \"exec:read l; printf '0 0 0 0'; sleep 30\"", 1,
       "answered '0 0 0 0' for step 0 but no newline followed within 0.5 s", rollout_out},
      // a child that closed its stdin and sleeps on: one message whether fetchscope's first write
      // came before the close (the pipe then reports its reader gone while fetchscope waits) or
      // after it (EPIPE); the timeout is long, so only seeing the close itself ends the wait in
      // time (issue 43: the row failed on slow hosts when the two ways had two messages)
      {"ExecClosesItsStdin", rollout + "--exec-timeout 60 --policy \"exec:exec 0<&-; sleep 90\"", 1,
       "closed its input (stdin) and kept running without answering step 0", rollout_out},
      {"ExecClosesItsStdinAfterReading",
       rollout + "--exec-timeout 60 --policy \"exec:read l; exec 0<&-; sleep 90\"", 1,
       "closed its input (stdin) and kept running without answering step 0", rollout_out},
      {"ExecClosesItsStdinAfterAStep",
       rollout + "--exec-timeout 60 --policy \"exec:read l; echo 0 0 0 0; exec 0<&-; sleep 90\"", 1,
       "closed its input (stdin) and kept running without answering step 1", rollout_out},
      // ---- --out reuse, --replay-dtype (issue 13)
      {"RecordOverwriteAndResume", record + "--overwrite --resume", 2, "--resume", kRecordOutputs},
      {"RecordOutHoldsARun",
       record,
       2,
       "already holds a record run",
       {"out/episode_000.mp4"},
       // a record manifest (a bare "{}" is not fetchscope's, and is refused as the user's)
       file("out/manifest.json", R"({"env_id": "FetchReach-v4", "seed": 0, "episodes": []})")},
      {"ReplayDtypeUnknown",
       rollout + "--policy replay:{src}/tests/data/replay/replay.csv "
                 "--replay-dtype float16",
       2, "float16", rollout_out},
      {"ReplayDtypeNotReplay", rollout + "--replay-dtype float32", 2, "--replay-dtype",
       rollout_out},
      {"ReplayDtypeNpyDisagrees",
       rollout + "--policy replay:{src}/tests/data/replay/replay_f64.npy "
                 "--replay-dtype float32",
       2, "float64", rollout_out},
      // ---- outputs that cannot be written (exit 2: the path as given), or a full disk (ulimit -f:
      // writes fail with EFBIG; exit 1)
      {"JsonOutParentIsFile",
       "describe --json-out {tmp}/f/d.json",
       2,
       "{tmp}/f",
       {"f/d.json"},
       file("f", "x")},
      {"JsonOutFileInTheWayOfFolder",
       "rollout --json-out {tmp}/f/such/r.json",
       2,
       "{tmp}/f/such",
       {"f/such/r.json"},
       file("f", "x")},
      {"RenderOutputFileInTheWayOfFolder",
       "render -o {tmp}/f/new/x.png",
       2,
       "{tmp}/f/new",
       {"f/new/x.png"},
       file("f", "x")},
      {"RenderOutputParentIsFile",
       "render -o {tmp}/f/x.png",
       2,
       "{tmp}/f",
       {"f/x.png"},
       file("f", "x")},
      {"RecordOutIsFile",
       "record --quiet --steps 3 --out {tmp}/f",
       2,
       "{tmp}/f",
       {},
       file("f", "x")},
      {"RecordOutUnwritable",
       "record --quiet --steps 3 --out {tmp}/ro/out",
       2,
       "{tmp}/ro",
       {"ro/out/episode_000.mp4", "ro/out/manifest.json"},
       [](const fs::path& tmp) {
         fs::create_directory(tmp / "ro");
         fs::permissions(tmp / "ro", fs::perms::owner_read | fs::perms::owner_exec |
                                         fs::perms::others_read | fs::perms::others_exec);
         fs::permissions(tmp, fs::perms::all);
         return true;
       },
       Unprivileged()},
      {"JsonOutFileSizeLimit",
       "rollout --episodes 3 --json-out {tmp}/r.json",
       1,
       "r.json",
       {"r.json"},
       {},
       kUlimit},
      {"DescribeFileSizeLimit",
       "describe --json-out {tmp}/d.json",
       1,
       "d.json",
       {"d.json"},
       {},
       "trap '' XFSZ; ulimit -f 1; "},
      {"RenderFileSizeLimit",
       "render --width 256 --height 256 -o {tmp}/f.png",
       1,
       "f.png",
       {"f.png"},
       {},
       "trap '' XFSZ; ulimit -f 2; "},
      {"RecordFileSizeLimit",
       "record --env-id FetchReach-v4 --quiet --width 320 --height 240 "
       "--steps 20 --out {tmp}/out",
       1,
       "File too large",
       kRecordOutputs,
       {},
       kUlimit},
      {"RandomEpisodesFileSizeLimit",
       "random-episodes --n-episodes 5 --json-out {tmp}/m",
       1,
       "m_random_metrics.json",
       {"m_random_metrics.json"},
       {},
       "trap '' XFSZ; ulimit -f 1; "},
  };
}

// gtest prints a failing row by this (instead of its bytes).
void PrintTo(const Case& c, std::ostream* os) { *os << c.name << ": " << c.args; }

class BadInput : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override { unsetenv("DISPLAY"); }
};

// Leftover temporaries anywhere under `root`: outputs are written under hidden names
// (".<name>.tmp-<pid>-<n>", ".episode_000.partial.mp4") and renamed when complete.
std::vector<std::string> Temporaries(const fs::path& root) {
  std::vector<std::string> found;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(root, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (it->path().filename().string()[0] == '.') found.push_back(it->path().string());
  }
  return found;
}

TEST_P(BadInput, FailsCleanly) {
  const Case& c = GetParam();
  if (c.skip) GTEST_SKIP() << c.skip;
  TempDir tmp;
  if (c.setup && !c.setup(tmp.path())) GTEST_SKIP() << "genuine assets absent";
  const std::string command =
      c.prefix + std::string(FETCHSCOPE_BIN) + " " + Expand(c.args, tmp.path()) + " </dev/null";
  const CommandResult r = RunCommand(command);
  const std::string& out = r.output;
  SCOPED_TRACE("command: " + command + "\noutput:\n" + out);

  EXPECT_EQ(r.exit_code, c.exit_code);
  EXPECT_NE(out.find(Expand(c.needle, tmp.path())), std::string::npos)
      << "the message does not name '" << Expand(c.needle, tmp.path()) << "'";
  // one clear line, not a dump: a few lines at most, each short enough to read
  EXPECT_LE(std::count(out.begin(), out.end(), '\n'), 4);
  EXPECT_LE(out.size(), 1200u);
  for (const char* crash : {"terminate called", "Aborted", "core dumped", "Segmentation fault",
                            "AddressSanitizer", "runtime error:", "what():", "Assertion"}) {
    EXPECT_EQ(out.find(crash), std::string::npos) << "abort text: " << crash;
  }
  for (const std::string& rel : c.absent) {
    EXPECT_FALSE(fs::exists(tmp.path() / rel)) << "a file under a final name: " << rel;
  }
  EXPECT_EQ(Temporaries(tmp.path()), std::vector<std::string>{});
  // restore permissions so that TempDir can clean up
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(tmp.path(), ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    fs::permissions(it->path(), fs::perms::owner_all, fs::perm_options::add, ec);
  }
}

INSTANTIATE_TEST_SUITE_P(Matrix, BadInput, ::testing::ValuesIn(Matrix()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return std::string(info.param.name);
                         });

// A full disk (a 16 KiB tmpfs in a private mount namespace): the write fails with ENOSPC, the
// message says so, and the folder holds no file under a final name and no temporary. Needs
// unshare + mount (root or user namespaces); skipped where they are not allowed.
struct FullDiskCase {
  const char* name;
  std::string args;  // {dir} is the full file system
  std::string needle;
};

class FullDisk : public ::testing::TestWithParam<FullDiskCase> {};

TEST_P(FullDisk, FailsCleanly) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string dir = (tmp.path() / "full").string();
  fs::create_directory(dir);
  const std::string mount = "unshare -m sh -c 'mount -t tmpfs -o size=16k tmpfs " + dir;
  if (RunCommand(mount + "'").exit_code != 0) GTEST_SKIP() << "cannot mount a tmpfs here";
  std::string args = GetParam().args;
  args.replace(args.find("{dir}"), 5, dir);
  // list what is left on the tmpfs before the namespace (and the tmpfs) goes away
  const CommandResult r = RunCommand(mount + " && " + FETCHSCOPE_BIN + " " + args +
                                     " </dev/null; rc=$?; echo listing:; ls -A " + dir + " " + dir +
                                     "/out 2>/dev/null; exit $rc'");
  SCOPED_TRACE(r.output);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find(GetParam().needle), std::string::npos);
  EXPECT_NE(r.output.find("No space left on device"), std::string::npos);
  const std::string listing = r.output.substr(r.output.find("listing:") + 8);
  for (const char* name : {"episode_000", "manifest.json", "r.json", ".tmp-", ".partial"}) {
    EXPECT_EQ(listing.find(name), std::string::npos) << name << " left on the full disk";
  }
}

INSTANTIATE_TEST_SUITE_P(
    Matrix, FullDisk,
    ::testing::Values(
        FullDiskCase{"Record",
                     "record --env-id FetchReach-v4 --quiet --width 320 --height 240 --steps 20 "
                     "--out {dir}/out",
                     "episode_000"},
        FullDiskCase{"RolloutJson", "rollout --episodes 3 --json-out {dir}/r.json", "r.json"}),
    [](const ::testing::TestParamInfo<FullDiskCase>& info) {
      return std::string(info.param.name);
    });

struct Mistake {
  std::string args;
  std::vector<std::string> needles;  // all in the one error line
};

TEST(RoughEdges, MistypedFlagsGetOneLineNamingTheOptionAndTheSubcommandsHelp) {
  const std::vector<Mistake> mistakes = {
      {"record --episode 3",
       {"--episode", "did you mean '--episodes'?", "fetchscope record --help"}},
      {"record --overlay=", {"--overlay", "needs a value", "fetchscope record --help"}},
      {"record --episodes 2 --episodes 3",
       {"--episodes", "given 2 times", "fetchscope record --help"}},
      {"record --hud-opacity abc",
       {"--hud-opacity", "'abc'", "number", "fetchscope record --help"}},
      {"render --widht 4 -o x.png",
       {"--widht", "did you mean '--width'?", "fetchscope render --help"}},
      {"rollout --episodes x", {"--episodes", "'x'", "whole number", "fetchscope rollout --help"}},
      {"record --policy scriptd", {"'scriptd'", "did you mean 'scripted'?"}},
  };
  for (const Mistake& m : mistakes) {
    SCOPED_TRACE(m.args);
    const CommandResult r = RunFetchscope(m.args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    const std::vector<std::string> lines = LinesWith(r.output, "error:");
    ASSERT_EQ(lines.size(), 1u) << r.output;
    EXPECT_EQ(r.output, lines[0] + "\n");
    for (const std::string& needle : m.needles) {
      EXPECT_NE(lines[0].find(needle), std::string::npos) << needle << " in " << lines[0];
    }
    for (const char* raw : {"not expected", "At Most", "Could not convert", "required TEXT",
                            "see fetchscope --help"}) {
      EXPECT_EQ(lines[0].find(raw), std::string::npos) << raw << " in " << lines[0];
    }
  }
}

struct AnatomyBadInput {
  std::string args;
  int exit_code;
  std::string message;  // substring of the one-line error
};

// gtest prints the command line instead of the bytes of the struct
void PrintTo(const AnatomyBadInput& c, std::ostream* os) { *os << c.args; }

class BadInputTest : public ::testing::TestWithParam<AnatomyBadInput> {};

TEST_P(BadInputTest, OneClearLineAndNoOutputFile) {
  TempDir tmp;
  const fs::path bad = tmp.path() / "bad";
  fs::create_directories(bad / "fetch");
  std::ofstream(bad / "fetch" / "reach.xml") << "<mujoco><worldbody><body name='x'></mujoco>";
  std::ofstream(bad / "fetch" / "push.xml") << "<mujoco/>";
  std::ofstream(tmp.path() / "nan.csv") << "0,0,0,0\nnan,0,0,0\n";
  std::ofstream(tmp.path() / "three.csv") << "0,0,0\n";
  std::ofstream(tmp.path() / "empty.csv") << "";
  std::ofstream(tmp.path() / "text.csv") << "hello,world\nfoo,bar\n";
  std::string args = GetParam().args;
  for (auto [key, value] : {std::pair<std::string, std::string>{"TMP", tmp.path().string()}}) {
    size_t pos;
    while ((pos = args.find(key)) != std::string::npos) args.replace(pos, key.size(), value);
  }
  const std::string out = (tmp.path() / "out.json").string();
  auto r = RunFetchscope(args + " --json-out " + out);
  EXPECT_EQ(r.exit_code, GetParam().exit_code) << r.output;
  EXPECT_NE(r.output.find(GetParam().message), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("fetchscope: error: "), std::string::npos) << r.output;
  EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 2) << r.output;
  EXPECT_EQ(r.output.find("terminate"), std::string::npos);
  EXPECT_EQ(r.output.find("Abort"), std::string::npos);
  EXPECT_FALSE(fs::exists(out));
  for (const auto& entry : fs::directory_iterator(tmp.path())) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Anatomy, BadInputTest,
    ::testing::Values(
        AnatomyBadInput{
            "describe --env-id FetchReach-v9", 2,
            "unknown env id 'FetchReach-v9' (did you mean 'FetchReach-v4'?): use one of "
            "FetchReach-v4"},
        AnatomyBadInput{"describe --assets TMP/missing", 2,
                        "missing' does not exist: use bundled, auto"},
        AnatomyBadInput{"describe --assets TMP", 2, "has no fetch/reach.xml"},
        AnatomyBadInput{"describe --env-id FetchReach-v4 --assets TMP/bad", 1,
                        "bad/fetch/reach.xml': XML parse error"},
        AnatomyBadInput{"random-episodes --seed -3", 2, "--seed '-3' is not valid"},
        AnatomyBadInput{"random-episodes --seed 99999999999999999999999", 2, "is too large"},
        AnatomyBadInput{"random-episodes --n-episodes 0", 2, "--n-episodes"},
        AnatomyBadInput{"rollout --policy greedy", 2, "unknown policy 'greedy'"},
        AnatomyBadInput{"rollout --steps 5 --policy replay:TMP/nan.csv", 1, "not a finite number"},
        AnatomyBadInput{"rollout --steps 1 --policy replay:TMP/three.csv", 1, "three.csv"},
        AnatomyBadInput{"rollout --steps 1 --policy replay:TMP/empty.csv", 1, "empty"},
        AnatomyBadInput{"rollout --steps 1 --policy replay:TMP/text.csv", 1, "text.csv"},
        AnatomyBadInput{"rollout --steps 5 --policy replay:TMP/missing.csv", 2, "missing.csv"},
        AnatomyBadInput{"rollout --steps 50 --policy replay:TMP/nan.csv", 1, "nan.csv"},
        AnatomyBadInput{"rollout --steps 3 --policy 'exec:exit 3'", 1, "exited with status 3"},
        AnatomyBadInput{"rollout --steps 3 --policy 'exec:echo hello; cat >/dev/null'", 1,
                        "answer 'hello'"},
        AnatomyBadInput{"rollout --steps 3 --exec-timeout 0.5 --policy 'exec:sleep 5'", 1,
                        "no answer for step 0 within 0.5 s"},
        AnatomyBadInput{"rollout --steps 10001", 2, "--steps"}));

// The rule of docs/reference/exit-codes.md, a command for each row: 0 for success; 1 for what
// fails while working (a file's contents, a policy); 2 for the command line, and a path on it
// that cannot be used as given is part of the command line: an input that does not exist or is
// a folder, an output that is a file or lies below one (and one that may not be written, where
// the tests do not run as root). SIGINT/SIGTERM's 130/143: tests/signals_test.cc.
TEST(ExitCodeRule, EveryRowOfTheTable) {
  TempDir tmp;
  const std::string t = tmp.path().string();
  std::ofstream(tmp.path() / "file") << "x";
  std::ofstream(tmp.path() / "text.csv") << "hello,world\n";
  fs::create_directories(tmp.path() / "folder.csv");
  const std::string reach = "--env-id FetchReach-v4 --steps 2 ";
  struct Row {
    std::string args;
    int exit_code;
    std::string message;
  };
  std::vector<Row> rows = {
      {"describe --env-id FetchReach-v4", 0, ""},
      // 1: found while working
      {"rollout " + reach + "--policy replay:" + t + "/text.csv", 1, "text.csv"},
      {"rollout " + reach + "--policy 'exec:exit 3'", 1, "exited with status 3"},
      // 2: the command line, paths included
      {"rollout --env-id FetchReach-v9", 2, "unknown env id"},
      {"rollout " + reach + "--policy replay:" + t + "/missing.csv", 2,
       "missing.csv: No such file or directory"},
      {"rollout " + reach + "--policy replay:" + t + "/folder.csv", 2, "it is a folder"},
      {"record --from " + t + "/missing-run --out " + t + "/r", 2, "missing-run"},
      {"export " + t + "/missing-run --minari x-v0", 2, "missing-run"},
      {"record " + reach + "--episodes 1 --quiet --out " + t + "/file", 2,
       "cannot create output folder '" + t + "/file'"},
      {"record " + reach + "--episodes 1 --quiet --out " + t + "/file/run", 2,
       "cannot create output folder '" + t + "/file/run': Not a directory"},
      {"rollout " + reach + "--json-out " + t + "/file/r.json", 2, "Not a directory"},
      {"render --env-id FetchReach-v4 --width 32 --height 32 -o " + t + "/file/f.png", 2,
       "Not a directory"},
      {"rollout " + reach + "--minari x-v0 --minari-root " + t + "/file/datasets", 2,
       "Not a directory"},
      {"probe-actions --env-id FetchReach-v4 --steps 1 --out " + t + "/file", 2,
       "cannot create output folder '" + t + "/file'"},
  };
  if (geteuid() != 0) {  // root writes into read-only folders
    fs::create_directories(tmp.path() / "ro");
    fs::permissions(tmp.path() / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    rows.push_back({"record " + reach + "--episodes 1 --quiet --out " + t + "/ro/run", 2,
                    "Permission denied"});
  }
  for (const Row& row : rows) {
    SCOPED_TRACE(row.args);
    const auto r = RunFetchscope(row.args + " 2>&1");
    EXPECT_EQ(r.exit_code, row.exit_code) << r.output;
    if (row.exit_code != 0) {
      EXPECT_EQ(testing::Count(r.output, "fetchscope: error: "), 1) << r.output;
      EXPECT_NE(r.output.find(row.message), std::string::npos) << r.output;
    }
  }
  EXPECT_FALSE(fs::exists(tmp.path() / "r"));
  std::error_code ignored;  // absent as root
  fs::permissions(tmp.path() / "ro", fs::perms::owner_all, ignored);
}

}  // namespace
}  // namespace fetchscope
