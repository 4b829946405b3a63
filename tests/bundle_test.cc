// tools/bundle.sh: the relocatable tarball for nodes without our Debian packages. Unpacked into
// a temporary folder, every library the binary needs (its ELF dependencies and the GL
// dispatchers it opens at run time) resolves inside the bundle, except glibc and GL vendor
// libraries, which must come from the node; and the bundled binary records an episode.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::RunCommand;
using testing::TempDir;
namespace fs = std::filesystem;

// glibc's libraries and the GL vendor/driver ones: never in the bundle.
const std::set<std::string> kNodeLibraries = {
    "linux-vdso.so.1", "ld-linux-x86-64.so.2", "libc.so.6",          "libm.so.6",
    "libmvec.so.1",    "libpthread.so.0",      "libdl.so.2",         "librt.so.1",
    "libresolv.so.2",  "libutil.so.1",         "libEGL_mesa.so.0",   "libGLX_mesa.so.0",
    "libOSMesa.so.8",  "libEGL_nvidia.so.0",   "libGLX_nvidia.so.0", "libcuda.so.1"};

class BundleTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tmp_ = new TempDir;
    const fs::path build = fs::path(FETCHSCOPE_BIN).parent_path();
    // ctest makes the bundle once for all four tests (the fixture test BundleMake, about 20 s,
    // names its folder in FETCHSCOPE_TEST_BUNDLE_DIR); run alone, each test process makes its own
    const char* made_once = std::getenv("FETCHSCOPE_TEST_BUNDLE_DIR");
    fs::path dist = tmp_->path();
    if (made_once != nullptr && *made_once != '\0') {
      dist = made_once;
      bundle_output_ = testing::ReadFile(dist / "bundle.log");  // what tools/bundle.sh said
      if (bundle_output_.empty())
        bundle_output_ = "no archive in " + dist.string() + " (see the test BundleMake)";
    } else {
      const CommandResult made =
          RunCommand("cd " + testing::SourceDir().string() + " && DIST_DIR=" + dist.string() +
                     " XZ_LEVEL=0 tools/bundle.sh " + build.string());
      bundle_output_ = made.output;
      if (made.exit_code != 0) return;
    }
    if (!fs::is_directory(dist)) return;
    for (const auto& e : fs::directory_iterator(dist)) {
      if (e.path().extension() == ".xz") archive_ = e.path();
    }
    if (archive_.empty()) return;
    RunCommand("tar -C " + tmp_->path().string() + " -xf " + archive_.string());
    root_ = tmp_->path() / archive_.stem().stem();
  }
  static void TearDownTestSuite() { delete tmp_; }
  void SetUp() override {
    ASSERT_FALSE(archive_.empty()) << bundle_output_;
    ASSERT_TRUE(fs::is_directory(root_ / "lib")) << root_;
  }
  static TempDir* tmp_;
  static std::string bundle_output_;
  static fs::path archive_, root_;
};
TempDir* BundleTest::tmp_ = nullptr;
std::string BundleTest::bundle_output_;
fs::path BundleTest::archive_, BundleTest::root_;

// One test for what the archive holds (made once per ctest run by BundleMake):
// its name and layout, the libraries a bare CUDA image lacks and none of glibc or the driver
// (names compared whole: libcjson.so.1 is not glibc's libc.so.6), every dependency resolving
// inside it with the launcher's library path, and the label font beside the binary.
TEST_F(BundleTest, HoldsWhatANodeLacksAndNothingOfGlibcOrTheDriver) {
  SCOPED_TRACE(bundle_output_);
  EXPECT_EQ(archive_.filename().string().rfind("fetchscope-", 0), 0u) << archive_;
  EXPECT_NE(archive_.filename().string().find("-linux-x86_64.tar.xz"), std::string::npos);
  EXPECT_TRUE(fs::exists(root_ / "fetchscope"));
  EXPECT_TRUE(fs::exists(root_ / "bin" / "fetchscope"));
  EXPECT_TRUE(fs::exists(root_ / "bin" / "models" / "push.xml"));
  EXPECT_NE(bundle_output_.find("needs glibc >="), std::string::npos) << bundle_output_;

  std::set<std::string> libs;
  for (const fs::path& dir : {root_ / "lib", root_ / "lib" / "cxx"}) {
    for (const auto& e : fs::directory_iterator(dir)) {
      if (e.is_regular_file()) libs.insert(e.path().filename());
    }
  }
  for (const char* needed :
       {"libavcodec.so.59", "libavformat.so.59", "libswscale.so.6", "libmujoco.so.2.2.2",
        "libpng16.so.16", "libEGL.so.1", "libGLdispatch.so.0", "libOpenGL.so.0", "libGL.so.1",
        "libcjson.so.1", "libx264.so.164", "libavfilter.so.8", "libvpx.so.7", "libcrypto.so.3",
        "libfreetype.so.6", "libfontconfig.so.1"}) {
    EXPECT_TRUE(libs.count(needed)) << needed;
  }
  // the C++ runtime sits apart, for the launcher to use only where the node's is too old
  EXPECT_TRUE(fs::exists(root_ / "lib" / "cxx" / "libstdc++.so.6"));
  EXPECT_FALSE(fs::exists(root_ / "lib" / "libstdc++.so.6"));
  for (const std::string& lib : libs) {
    EXPECT_FALSE(kNodeLibraries.count(lib)) << lib << " must come from the node";
    EXPECT_EQ(lib.rfind("libnvidia-", 0), std::string::npos) << lib;
  }

  // ldd of the binary and of every bundled library, with the library path the launcher sets
  // where the node's C++ runtime is too old (lib and lib/cxx): every dependency resolves
  // inside the bundle, except glibc's
  std::vector<fs::path> objects = {root_ / "bin" / "fetchscope"};
  for (const fs::path& dir : {root_ / "lib", root_ / "lib" / "cxx"}) {
    for (const auto& e : fs::directory_iterator(dir)) {
      if (e.is_regular_file()) objects.push_back(e.path());
    }
  }
  const std::string lib = fs::canonical(root_ / "lib").string();
  for (const fs::path& object : objects) {
    const CommandResult ldd =
        RunCommand("LD_LIBRARY_PATH=" + lib + ":" + lib + "/cxx ldd " + object.string());
    std::istringstream lines(ldd.output);
    for (std::string line; std::getline(lines, line);) {
      const size_t arrow = line.find("=>");
      if (arrow == std::string::npos) continue;
      std::string name = line.substr(0, arrow);
      name.erase(0, name.find_first_not_of(" \t"));
      name.erase(name.find_last_not_of(" \t") + 1);
      EXPECT_EQ(line.find("not found"), std::string::npos) << object << ": " << line;
      if (kNodeLibraries.count(name)) continue;
      EXPECT_NE(line.find(lib + "/"), std::string::npos)
          << object.filename() << " takes " << name << " from outside the bundle: " << line;
    }
  }

  // the label font travels beside the binary, where render/text.h looks first
  const fs::path font = root_ / "bin" / "fonts" / "DejaVuSans.ttf";
  ASSERT_TRUE(fs::is_regular_file(font)) << font;
  EXPECT_EQ(testing::ReadFile(font),
            testing::ReadFile("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"));
}

// The launcher takes the node's C++ runtime when it has every version the bundle needs (this
// Debian machine's does: it built the binary), and the bundled one when the node's is older
// (a file without those version strings stands in for it). ld.so's log says which was loaded.
// A release file: readable by the group and others (mktemp made it 0600 before issue 19),
// whatever the umask, and writable only by its owner.
TEST_F(BundleTest, ArchiveIsReadableByEveryone) {
  const fs::perms p = fs::status(archive_).permissions();
  EXPECT_EQ(p & fs::perms::all, fs::perms(0644))
      << archive_ << " mode " << std::oct << static_cast<int>(p & fs::perms::all);
}

TEST_F(BundleTest, LauncherPrefersTheNodesCxxRuntimeUnlessItIsTooOld) {
  const std::string launcher = (root_ / "fetchscope").string();
  auto loaded_from = [&](const std::string& env) {
    const CommandResult r =
        RunCommand(env + " LD_DEBUG=libs " + launcher +
                   " list-envs 2>&1 >/dev/null | grep 'calling init:.*libstdc'");
    std::istringstream lines(r.output);
    for (std::string line; std::getline(lines, line);) {
      if (line.find("calling init:") != std::string::npos &&
          line.find("libstdc++.so.6") != std::string::npos) {
        return line.substr(line.find("calling init:") + 14);
      }
    }
    return std::string("(libstdc++ not loaded)\n") + r.output.substr(0, 2000);
  };
  const std::string bundled = fs::canonical(root_ / "lib" / "cxx").string() + "/libstdc++.so.6";
  EXPECT_NE(loaded_from(""), bundled);
  EXPECT_EQ(loaded_from("").find(root_.string()), std::string::npos) << loaded_from("");
  TempDir old;
  const fs::path old_runtime = old.path() / "libstdc++.so.6";
  std::ofstream(old_runtime) << "GLIBCXX_3.4 GLIBCXX_3.4.21 CXXABI_1.3";
  EXPECT_EQ(loaded_from("FETCHSCOPE_HOST_LIBSTDCXX=" + old_runtime.string()), bundled);
  EXPECT_EQ(loaded_from("FETCHSCOPE_HOST_LIBSTDCXX=/nonexistent"), bundled);
}

// The launcher, called through a symbolic link from elsewhere, records an episode that plays,
// in every format, with its contact sheet (text through the bundled FreeType and font).
TEST_F(BundleTest, BundledBinaryRecordsAnEpisode) {
  TempDir work;
  fs::create_symlink(root_ / "fetchscope", work.path() / "fs");
  const CommandResult r = RunCommand(
      "cd " + work.path().string() +
      " && env -u MUJOCO_GL ./fs record --env-id FetchPush-v4 --policy scripted --episodes 1 "
      "--steps 5 --width 64 --height 64 --quiet --format mp4,webm,gif,apng --out run");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const auto& [file, expected] :
       std::vector<std::pair<std::string, std::string>>{{"episode_000.mp4", "h264,6\n"},
                                                        {"episode_000.webm", "vp9,6\n"},
                                                        {"episode_000.gif", "gif,3\n"},
                                                        {"episode_000.apng", "apng,6\n"}}) {
    const fs::path video = work.path() / "run" / file;
    const CommandResult probe = RunCommand(
        "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
        "stream=codec_name,nb_read_frames -of csv=p=0 " +
        video.string());
    EXPECT_EQ(probe.output, expected) << file;
  }
  EXPECT_TRUE(fs::is_regular_file(work.path() / "run" / "episode_000_sheet.png"));
  const CommandResult version = RunCommand((root_ / "fetchscope").string() + " --version");
  EXPECT_EQ(version.exit_code, 0) << version.output;
}

// The README tour's golden check, from a folder outside any checkout: the bundle's own goldens
// (bin/golden, beside the binary) are found without --golden-dir, and its examples are where
// `help --examples-dir` says.
TEST_F(BundleTest, GoldenCheckFromAnyFolderUsesTheBundlesGoldens) {
  TempDir work;
  const CommandResult r = RunCommand(
      "cd " + work.path().string() + " && env -u MUJOCO_GL " + (root_ / "fetchscope").string() +
      " golden check --backend osmesa --only reach_reset,slide_reset --out golden-failures 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(
      r.output.find("2 scene(s) from " + (root_ / "bin" / "golden" / "manifest.json").string()),
      std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("all 2 scene(s) pass"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(work.path() / "golden-failures"));
  const CommandResult examples =
      RunCommand("cd " + work.path().string() + " && " + (root_ / "fetchscope").string() +
                 " help --examples-dir");
  ASSERT_EQ(examples.exit_code, 0) << examples.output;
  const fs::path dir = examples.output.substr(0, examples.output.find('\n'));
  EXPECT_EQ(dir, root_ / "bin" / "examples");
  EXPECT_TRUE(fs::is_regular_file(dir / "policies" / "mlp_policy.py")) << dir;
}

}  // namespace
}  // namespace fetchscope
