// AtomicFile: outputs appear whole on Commit() and never half-written.
#include "base/atomic_file.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cstdlib>
#include <functional>
#include <iostream>
#include <string>
#include <utility>

#include "base/errors.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReadFile;
using testing::TempDir;

size_t FileCount(const std::filesystem::path& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

std::string ErrorOf(const std::function<void()>& body) {
  try {
    body();
  } catch (const std::runtime_error& e) {  // UsageError for a path that cannot be, else RunError
    return e.what();
  }
  return "(no error)";
}

TEST(AtomicFileTest, TempPathIsHiddenBesideTheFinalPath) {
  const std::string pid = std::to_string(::getpid());
  const std::string a = TempPathFor("out/run/a.json");
  EXPECT_EQ(a.rfind("out/run/.a.json.tmp-" + pid + "-", 0), 0u) << a;
  EXPECT_NE(TempPathFor("out/run/a.json"), a);  // the counter moves on
  EXPECT_EQ(TempPathFor("b.png").rfind(".b.png.tmp-" + pid + "-", 0), 0u);
}

TEST(AtomicFileTest, CommitCreatesTheFileAndNothingElse) {
  TempDir dir;
  const std::string path = (dir.path() / "a.json").string();
  {
    AtomicFile file(path);
    file.Write("{\"x\": ");
    std::fputs("1}\n", file.file());  // C writers share the same FILE
    EXPECT_TRUE(std::filesystem::exists(file.temp_path()));
    EXPECT_FALSE(std::filesystem::exists(path));  // invisible until committed
    file.Commit();
    EXPECT_EQ(file.file(), nullptr);
  }
  EXPECT_EQ(ReadFile(path), "{\"x\": 1}\n");
  EXPECT_EQ(FileCount(dir.path()), 1u);
}

TEST(AtomicFileTest, CommitReplacesAnExistingFile) {
  TempDir dir;
  const std::string path = (dir.path() / "manifest.json").string();
  WriteFileAtomically(path, "old");
  WriteFileAtomically(path, std::string("new\0bytes", 9));
  EXPECT_EQ(ReadFile(path), std::string("new\0bytes", 9));
  EXPECT_EQ(FileCount(dir.path()), 1u);
}

TEST(AtomicFileTest, DestructionWithoutCommitLeavesNothing) {
  TempDir dir;
  const std::string path = (dir.path() / "episode_000.mp4").string();
  {
    AtomicFile file(path);
    file.Write(std::string(100000, 'x'));
  }
  EXPECT_EQ(FileCount(dir.path()), 0u);

  // an existing file is left as it was
  WriteFileAtomically(path, "kept");
  {
    AtomicFile file(path);
    file.Write("lost");
  }
  EXPECT_EQ(ReadFile(path), "kept");
  EXPECT_EQ(FileCount(dir.path()), 1u);
}

TEST(AtomicFileTest, MovesTransferOwnership) {
  TempDir dir;
  const std::string path = (dir.path() / "m.txt").string();
  AtomicFile first(path);
  first.Write("moved");
  AtomicFile second(std::move(first));
  EXPECT_EQ(first.file(), nullptr);  // NOLINT(bugprone-use-after-move): documented moved-from state
  AtomicFile third((dir.path() / "other.txt").string());
  third = std::move(second);  // discards other.txt's temporary
  EXPECT_EQ(FileCount(dir.path()), 1u);
  third.Commit();
  EXPECT_EQ(ReadFile(path), "moved");
  EXPECT_EQ(FileCount(dir.path()), 1u);
}

TEST(AtomicFileTest, UnwritableFolderNamesTheFolder) {
  TempDir dir;
  // tests run as root, where mode bits do not stop writes: use a missing folder and a regular
  // file in the folder's place instead
  EXPECT_EQ(ErrorOf([] { WriteFileAtomically("/etc/hostname/x.json", "{}"); }),
            "cannot write to folder '/etc/hostname': Not a directory");
  EXPECT_EQ(ErrorOf([&] { AtomicFile file(dir.path().string() + "/"); }),
            "cannot write '" + dir.path().string() + "/': it names a folder, not a file");
  EXPECT_EQ(FileCount(dir.path()), 0u);
}

TEST(AtomicFileTest, MissingParentFoldersAreCreated) {
  TempDir dir;
  const std::filesystem::path path = dir.path() / "results" / "deep" / "ch01_env_describe.json";
  WriteFileAtomically(path.string(), "{}\n");
  EXPECT_EQ(ReadFile(path), "{}\n");
  EXPECT_EQ(FileCount(dir.path() / "results" / "deep"), 1u);  // no temporary left

  // a relative path with a bare folder name, as the course types it
  const std::filesystem::path cwd = std::filesystem::current_path();
  std::filesystem::current_path(dir.path());
  WriteFileAtomically("results2/x.json", "1");
  std::filesystem::current_path(cwd);
  EXPECT_EQ(ReadFile(dir.path() / "results2" / "x.json"), "1");
}

TEST(AtomicFileTest, FoldersCreatedForAFileNeverCommittedAreRemoved) {
  TempDir dir;
  std::filesystem::create_directory(dir.path() / "kept");
  {
    AtomicFile file((dir.path() / "kept" / "new" / "newer" / "a.json").string());
    file.Write("lost");
    EXPECT_TRUE(std::filesystem::is_directory(dir.path() / "kept" / "new" / "newer"));
  }
  // the folders this write made are gone again; the one that was there stays
  EXPECT_TRUE(std::filesystem::is_directory(dir.path() / "kept"));
  EXPECT_EQ(FileCount(dir.path() / "kept"), 0u);

  // a folder that meanwhile holds someone else's file stays
  {
    ParentFolders parents((dir.path() / "a" / "b" / "c.png").string());
    EXPECT_EQ(parents.created().size(), 2u);
    WriteFileAtomically((dir.path() / "a" / "other.json").string(), "x");
  }
  EXPECT_TRUE(std::filesystem::exists(dir.path() / "a" / "other.json"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "a" / "b"));
}

TEST(AtomicFileTest, AFileInTheWayOfAParentFolderNamesIt) {
  TempDir dir;
  WriteFileAtomically((dir.path() / "f").string(), "x");
  const std::string in_the_way = (dir.path() / "f" / "sub").string();
  EXPECT_EQ(ErrorOf([&] { WriteFileAtomically(in_the_way + "/a.json", "{}"); }),
            "cannot create folder '" + in_the_way + "': Not a directory");
  EXPECT_EQ(FileCount(dir.path()), 1u);
}

TEST(AtomicFileTest, FinalPathThatIsAFolderFailsAtCommit) {
  TempDir dir;
  std::filesystem::create_directory(dir.path() / "taken");
  std::filesystem::create_directory(dir.path() / "taken" / "inside");
  const std::string path = (dir.path() / "taken").string();
  const std::string error = ErrorOf([&] { WriteFileAtomically(path, "x"); });
  EXPECT_EQ(error.rfind("cannot write '" + path + "': ", 0), 0u) << error;
  EXPECT_EQ(FileCount(dir.path()), 1u);  // no temporary left behind
}

TEST(AtomicFileTest, CommitTwiceIsAnError) {
  TempDir dir;
  AtomicFile file((dir.path() / "a").string());
  file.Commit();
  EXPECT_THROW(file.Commit(), RunError);
}

// A full disk cannot be simulated in-process without privileges, and /dev/full cannot hold a
// temporary file beside it. RLIMIT_FSIZE gives the same kind of failure from the kernel
// (EFBIG on write), inside a forked child so the limit does not leak into this process.
enum class WriteMode { kLargeWrite, kBufferedCWrites };

void WriteOverFileSizeLimit(const std::string& path, WriteMode mode) {
  struct rlimit limit = {1000, 1000};
  if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) std::_Exit(3);
  ::signal(SIGXFSZ, SIG_IGN);  // get EFBIG instead of being killed
  try {
    AtomicFile file(path);
    if (mode == WriteMode::kLargeWrite) {
      file.Write(std::string(1 << 20, 'x'));  // fails inside Write()
    } else {
      // a C writer's small writes stay in stdio's buffer: the failure surfaces in Commit()
      for (int i = 0; i < 200; ++i) std::fputs("0123456789", file.file());
    }
    file.Commit();
  } catch (const RunError& e) {
    std::cerr << e.what() << std::endl;
    std::_Exit(std::filesystem::exists(path) ? 4 : 0);
  }
  std::_Exit(5);
}

TEST(AtomicFileDeathTest, FailedWritesAreReportedAndLeaveNothing) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  TempDir dir;
  const std::string path = (dir.path() / "big.bin").string();
  EXPECT_EXIT(WriteOverFileSizeLimit(path, WriteMode::kLargeWrite), ::testing::ExitedWithCode(0),
              "writing '.*big.bin' failed: File too large");
  EXPECT_EXIT(WriteOverFileSizeLimit(path, WriteMode::kBufferedCWrites),
              ::testing::ExitedWithCode(0), "writing '.*big.bin' failed: File too large");
  EXPECT_EQ(FileCount(dir.path()), 0u);
}

}  // namespace
}  // namespace fetchscope
