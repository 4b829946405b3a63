// A hostile run folder (issue 44, item 4): a file it holds or its manifest names that leads
// outside it (a symbolic link, '..', an absolute path), one that is no regular file (a FIFO, a
// symbolic link to /dev/zero) or one far larger than any episode, read by report, compare,
// record --from, export and serve. Each is refused, exit non-zero, with one line naming the
// entry; nothing of the outside file's bytes shows; nothing is read without a bound (each
// command runs under a memory limit and a timeout). Black-box (the built fetchscope), and serve's
// sources in process.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "base/confined_file.h"
#include "base/errors.h"
#include "serve/sources.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::CommandResult;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;

// The outside file's first line: a JSON string that nlohmann's parse error would quote whole.
constexpr char kSecret[] = "FETCHSCOPE-SECRET-5b1e9c";

// One recorded run, made once for every test (each works on its own copy).
class HostileFolderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    unsetenv("DISPLAY");
    recorded_ = new TempDir;
    const CommandResult r = RunFetchscope(
        "record --quiet --env-id FetchReach-v4 --policy random --seed 3 --episodes 2 --steps 4 "
        "--width 48 --height 48 --overlay none --out " +
        (recorded_->path() / "run").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() {
    delete recorded_;
    recorded_ = nullptr;
  }

  void SetUp() override {
    ASSERT_TRUE(fs::exists(recorded_->path() / "run" / "manifest.json"));
    run_ = tmp_.path() / "run";
    fs::copy(recorded_->path() / "run", run_, fs::copy_options::recursive);
    fs::create_directories(tmp_.path() / "outside");
    secret_ = tmp_.path() / "outside" / "secret.json";
    std::ofstream(secret_) << "\"" << kSecret << " root:x:0:0:root:/root:/bin/bash\n"
                           << kSecret << "\n";
  }

  // Replaces `name` in the run folder by a symbolic link to `target`.
  void LinkInRun(const std::string& name, const fs::path& target) {
    fs::remove(run_ / name);
    fs::create_symlink(target, run_ / name);
  }

  // Sets episode `k`'s `key` in the run's manifest to `value`.
  void EditManifest(int k, const std::string& key, const std::string& value) {
    json m = json::parse(ReadFile(run_ / "manifest.json"));
    for (json& e : m["episodes"]) {
      if (e["index"] == k) e[key] = value;
    }
    std::ofstream(run_ / "manifest.json", std::ios::trunc) << m.dump(2);
  }

  // `fetchscope ARGS` under a 4 GiB address-space limit and a 30 s timeout: a command that reads
  // without a bound fails here (out of memory, or killed) instead of taking the machine.
  static CommandResult Bounded(const std::string& args, double* seconds = nullptr) {
    const auto start = std::chrono::steady_clock::now();
    CommandResult r = RunCommand("ulimit -v 4194304; exec timeout -s KILL 30 " +
                                 std::string(FETCHSCOPE_BIN) + " " + args + " </dev/null");
    if (seconds) {
      *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return r;
  }

  // A refusal: a non-zero exit that is neither a crash nor the timeout, one error line that holds
  // every one of `says`, and nothing of the secret.
  static void ExpectRefused(const CommandResult& r, const std::vector<std::string>& says,
                            const std::string& what) {
    SCOPED_TRACE(what);
    EXPECT_TRUE(r.exit_code == 1 || r.exit_code == 2) << r.exit_code << "\n" << r.output;
    EXPECT_EQ(r.output.find(kSecret), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("root:x:0"), std::string::npos) << r.output;
    const std::vector<std::string> errors = testing::LinesWith(r.output, "fetchscope: error:");
    ASSERT_EQ(errors.size(), 1u) << r.output;
    for (const std::string& s : says) EXPECT_NE(errors[0].find(s), std::string::npos) << r.output;
  }

  // The commands that read a run folder by its manifest (report, compare) and by its episode
  // files (record --from, export), each refusing with `says`.
  // serve refuses at start what is wrong with the manifest or the files it names (outside, not
  // regular); a trajectory too large is refused when its episode is asked for (in process below).
  void ExpectEveryReaderRefuses(const std::vector<std::string>& says, bool by_manifest,
                                bool by_files, bool serve = true) {
    const std::string run = "'" + run_.string() + "'";
    if (by_manifest) {
      ExpectRefused(Bounded("report " + run), says, "report");
      EXPECT_FALSE(fs::exists(run_ / "index.html.tmp"));
      ExpectRefused(Bounded("compare " + run + " '" + (recorded_->path() / "run").string() +
                            "' --states-only --out '" + (tmp_.path() / "cmp").string() + "'"),
                    says, "compare");
      if (serve) {
        ExpectRefused(Bounded("serve " + run + " --port 0 --token-file '" +
                              (tmp_.path() / "token").string() + "'"),
                      says, "serve");
      }
    }
    if (by_files) {
      ExpectRefused(Bounded("record --quiet --width 48 --height 48 --from " + run + " --out '" +
                            (tmp_.path() / "again").string() + "'"),
                    says, "record --from");
      EXPECT_FALSE(fs::exists(tmp_.path() / "again" / "manifest.json"));
      ExpectRefused(Bounded("export " + run + " --minari hostile/run-v0 --minari-root '" +
                            (tmp_.path() / "minari").string() + "'"),
                    says, "export");
      EXPECT_FALSE(fs::exists(tmp_.path() / "minari" / "hostile" / "run-v0"));
    }
  }

  static TempDir* recorded_;
  TempDir tmp_;
  fs::path run_;
  fs::path secret_;
};

TempDir* HostileFolderTest::recorded_ = nullptr;

TEST_F(HostileFolderTest, EpisodeJsonLinkedToAFileOutside) {
  LinkInRun("episode_001.json", secret_);
  ExpectEveryReaderRefuses({"episode_001.json", "outside the run folder"}, true, true);
}

TEST_F(HostileFolderTest, ManifestEntryWithDotDot) {
  EditManifest(1, "trajectory", "../outside/secret.json");
  ExpectEveryReaderRefuses(
      {"manifest.json names episode 1's trajectory '../outside/secret.json'", "outside"}, true,
      false);
}

TEST_F(HostileFolderTest, ManifestEntryAbsolute) {
  EditManifest(0, "trajectory", secret_.string());
  ExpectEveryReaderRefuses({"episode 0's trajectory '" + secret_.string() + "'", "outside"}, true,
                           false);
  // any file an entry names, not only the trajectory: a sheet, a video
  std::ofstream(secret_.parent_path() / "sheet.png") << kSecret;
  EditManifest(0, "trajectory", "episode_000.json");
  EditManifest(1, "sheet", (secret_.parent_path() / "sheet.png").string());
  ExpectRefused(Bounded("report '" + run_.string() + "'"), {"episode 1's sheet", "outside"},
                "report, sheet");
  EditManifest(1, "sheet", "episode_001_sheet.png");
  EditManifest(1, "video", "/etc/hostname");
  ExpectRefused(Bounded("report '" + run_.string() + "'"), {"episode 1's video '/etc/hostname'"},
                "report, video");
}

TEST_F(HostileFolderTest, ManifestLinkedToAFileOutside) {
  fs::copy_file(run_ / "manifest.json", tmp_.path() / "outside" / "manifest.json");
  LinkInRun("manifest.json", tmp_.path() / "outside" / "manifest.json");
  ExpectRefused(Bounded("report '" + run_.string() + "'"), {"manifest.json", "outside"}, "report");
}

TEST_F(HostileFolderTest, EpisodeJsonLinkedToDevZeroEndsAtOnce) {
  LinkInRun("episode_001.json", "/dev/zero");
  double seconds = 0;
  ExpectRefused(Bounded("report '" + run_.string() + "'", &seconds), {"episode_001.json"},
                "report");
  EXPECT_LT(seconds, 20);
  ExpectEveryReaderRefuses({"episode_001.json"}, true, true);
  // a trajectory named directly: no regular file, refused before a byte is read
  ExpectRefused(Bounded("export /dev/zero --minari hostile/zero-v0 --minari-root '" +
                            (tmp_.path() / "minari").string() + "'",
                        &seconds),
                {"/dev/zero", "not a regular file"}, "export /dev/zero");
  EXPECT_LT(seconds, 20);
}

TEST_F(HostileFolderTest, EpisodeJsonThatIsAFifo) {
  fs::remove(run_ / "episode_001.json");
  ASSERT_EQ(mkfifo((run_ / "episode_001.json").c_str(), 0600), 0);
  ExpectEveryReaderRefuses({"episode_001.json", "FIFO"}, true, true);
  // named directly
  const fs::path fifo = tmp_.path() / "t.json";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  ExpectRefused(Bounded("record --quiet --from '" + fifo.string() + "' --out '" +
                        (tmp_.path() / "direct").string() + "'"),
                {"t.json", "FIFO"}, "record --from FIFO");
}

TEST_F(HostileFolderTest, OversizedEpisodeJsonAndManifest) {
  // sparse: 300 MiB that cost no disk, refused by their size before they are read
  const uint64_t big = uint64_t{300} << 20;
  fs::resize_file(run_ / "episode_001.json", big);
  ExpectEveryReaderRefuses({"episode_001.json", "256 MiB"}, true, true, /*serve=*/false);
  const serve::Source source = serve::OpenSource(run_.string(), tmp_.path());
  EXPECT_THROW(serve::EpisodeRows(source, 1), UsageError);  // a 400
  ExpectRefused(Bounded("export '" + (run_ / "episode_001.json").string() +
                        "' --minari hostile/big-v0 --minari-root '" +
                        (tmp_.path() / "minari").string() + "'"),
                {"episode_001.json", "256 MiB"}, "export FILE");
  fs::resize_file(run_ / "manifest.json", big);
  ExpectRefused(Bounded("report '" + run_.string() + "'"), {"manifest.json", "256 MiB"},
                "report, manifest");
}

// A file inside the folder that is not JSON: its error names the file and the byte, never its
// bytes (nlohmann's message quotes what it last read: a first line that opens a string, whole).
TEST_F(HostileFolderTest, ParseErrorsQuoteNoBytes) {
  fs::copy_file(secret_, run_ / "episode_001.json", fs::copy_options::overwrite_existing);
  ExpectRefused(Bounded("record --quiet --width 48 --height 48 --from '" + run_.string() +
                        "' --out '" + (tmp_.path() / "again").string() + "'"),
                {"episode_001.json", "not JSON", "at byte"}, "record --from");
  ExpectRefused(Bounded("export '" + run_.string() + "' --minari hostile/p-v0 --minari-root '" +
                        (tmp_.path() / "minari").string() + "'"),
                {"episode_001.json", "not JSON"}, "export");
  // report notes an unreadable trajectory in its page: without the bytes there too
  const CommandResult report = Bounded("report '" + run_.string() + "'");
  EXPECT_EQ(report.output.find(kSecret), std::string::npos) << report.output;
  if (report.exit_code == 0) {
    const std::string page = ReadFile(run_ / "index.html");
    EXPECT_EQ(page.find(kSecret), std::string::npos);
    EXPECT_NE(page.find("at byte"), std::string::npos);
  }
  fs::copy_file(secret_, run_ / "manifest.json", fs::copy_options::overwrite_existing);
  ExpectRefused(Bounded("report '" + run_.string() + "'"), {"manifest.json", "not JSON", "byte"},
                "report, manifest");
}

// serve, in process: a hostile folder is refused when it is opened, and a folder changed after
// that is refused when the episode is read (the server answers 400 for a UsageError).
TEST_F(HostileFolderTest, ServeSourcesRefuseFilesOutside) {
  EditManifest(1, "trajectory", "../outside/secret.json");
  try {
    serve::OpenSource(run_.string(), tmp_.path());
    ADD_FAILURE() << "opened";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("'../outside/secret.json'"), std::string::npos)
        << e.what();
  }
  EditManifest(1, "trajectory", "episode_001.json");
  const serve::Source source = serve::OpenSource(run_.string(), tmp_.path());
  EXPECT_EQ(serve::EpisodeRows(source, 1).index, 1);
  LinkInRun("episode_001.json", secret_);
  try {
    serve::EpisodeRows(source, 1);
    ADD_FAILURE() << "read";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("outside the run folder"), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).find(kSecret), std::string::npos) << e.what();
  }
  LinkInRun("episode_001.json", "/dev/zero");
  EXPECT_THROW(serve::EpisodeRows(source, 1), UsageError);
}

// A merged run (merge-manifests m0 m1) names files in its shards' folders: those stay readable,
// and a shard the merged manifest claims is no widening of the folder unless a shard manifest is
// there.
TEST_F(HostileFolderTest, MergedRunReadsItsShardsFoldersOnly) {
  for (int i = 0; i < 2; ++i) {
    const CommandResult r = RunFetchscope(
        "record --quiet --env-id FetchReach-v4 --policy random --seed 3 --episodes 2 --steps 3 "
        "--width 32 --height 32 --overlay none --shard " +
        std::to_string(i) + "/2 --out '" + (tmp_.path() / ("m" + std::to_string(i))).string() +
        "'");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const fs::path m0 = tmp_.path() / "m0";
  CommandResult r = RunFetchscope("merge-manifests '" + m0.string() + "' '" +
                                  (tmp_.path() / "m1").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const serve::Source source = serve::OpenSource(m0.string(), tmp_.path());
  EXPECT_EQ(serve::EpisodeRows(source, 1).index, 1);  // ../m1/episode_001.json
  r = Bounded("report '" + m0.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // a shard claimed in a folder without its shard manifest: no folder of the run
  json m = json::parse(ReadFile(m0 / "manifest.json"));
  m["shards"][1]["manifest"] = "../outside/secret.json";
  std::ofstream(m0 / "manifest.json", std::ios::trunc) << m.dump(2);
  ExpectRefused(Bounded("report '" + m0.string() + "'"),
                {"episode 1's video '../m1/episode_001.mp4'", "outside"}, "report, merged");
}

// The reader itself: the cap holds while reading too (a /proc file says its size is 0).
TEST(ReadFileCapped, RefusesWhatIsNoRegularFileOrTooLarge) {
  TempDir tmp;
  std::ofstream(tmp.path() / "a.json") << "0123456789";
  EXPECT_EQ(ReadFileCapped(tmp.path() / "a.json", 10), "0123456789");
  EXPECT_THROW(ReadFileCapped(tmp.path() / "a.json", 9), UsageError);
  EXPECT_THROW(ReadFileCapped("/proc/self/maps", 16), UsageError);
  EXPECT_THROW(ReadFileCapped("/dev/zero", kMaxJsonFileBytes), UsageError);
  EXPECT_THROW(ReadFileCapped(tmp.path(), kMaxJsonFileBytes), UsageError);
  EXPECT_THROW(ReadFileCapped(tmp.path() / "none.json", kMaxJsonFileBytes), RunError);
  ASSERT_EQ(mkfifo((tmp.path() / "f.json").c_str(), 0600), 0);
  EXPECT_THROW(ReadFileCapped(tmp.path() / "f.json", kMaxJsonFileBytes), UsageError);
  // ResolveInside: '..' and links resolved; a name inside passes, missing or not
  fs::create_directories(tmp.path() / "run" / "sub");
  EXPECT_EQ(ResolveInside(tmp.path() / "run", "sub/../x.json", "m names"),
            tmp.path() / "run" / "sub/../x.json");
  EXPECT_THROW(ResolveInside(tmp.path() / "run", "../a.json", "m names"), UsageError);
  EXPECT_THROW(ResolveInside(tmp.path() / "run", "/etc/hostname", "m names"), UsageError);
  EXPECT_THROW(ResolveInside(tmp.path() / "run", "sub/../../run2/x", "m names"), UsageError);
  fs::create_directory_symlink(tmp.path(), tmp.path() / "run" / "up");
  EXPECT_THROW(ResolveInside(tmp.path() / "run", "up/a.json", "m names"), UsageError);
  try {
    ResolveInside(tmp.path() / "run", "../a.json", "manifest.json names trajectory");
  } catch (const UsageError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("manifest.json names trajectory '../a.json', which lies "
                                          "outside the run folder",
                                          0),
              0u)
        << e.what();
  }
}

}  // namespace
}  // namespace fetchscope
