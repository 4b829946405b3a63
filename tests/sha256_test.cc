// SHA-256 against the FIPS 180-4 / NIST example vectors and coreutils' sha256sum.
#include "base/sha256.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <string>

#include "base/errors.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::RunCommand;
using testing::TempDir;

void WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

// The hex digest sha256sum prints for a file.
std::string Sha256sum(const std::filesystem::path& path) {
  const auto result = RunCommand("sha256sum '" + path.string() + "'");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return result.output.substr(0, 64);
}

TEST(Sha256Test, NistVectors) {
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

// Feeding in pieces of every size crosses block boundaries at every offset.
TEST(Sha256Test, IncrementalEqualsOneShot) {
  std::string message;
  for (int i = 0; i < 1000; ++i) message.push_back(static_cast<char>(i * 131 % 256));
  for (size_t piece = 1; piece <= 130; ++piece) {
    Sha256 hash;
    for (size_t at = 0; at < message.size(); at += piece) {
      hash.Update(message.data() + at, std::min(piece, message.size() - at));
    }
    ASSERT_EQ(hash.HexDigest(), Sha256Hex(message)) << "piece " << piece;
  }
  Sha256 twice;
  twice.Update("abc", 3);
  EXPECT_EQ(twice.HexDigest(), twice.HexDigest());
}

// Lengths around the padding boundaries (55, 56, 63, 64 bytes) against coreutils.
TEST(Sha256Test, MatchesSha256sumOnFiles) {
  TempDir dir;
  for (size_t length : {0, 1, 55, 56, 57, 63, 64, 65, 119, 120, 128, 100000}) {
    std::string bytes;
    for (size_t i = 0; i < length; ++i) bytes.push_back(static_cast<char>((i * 7 + length) % 256));
    const auto path = dir.path() / ("f" + std::to_string(length));
    WriteBytes(path, bytes);
    EXPECT_EQ(Sha256Hex(bytes), Sha256sum(path)) << "length " << length;
    EXPECT_EQ(Sha256OfFile(path), Sha256sum(path)) << "length " << length;
  }
}

TEST(Sha256Test, MissingFileIsRunError) {
  TempDir dir;
  try {
    Sha256OfFile(dir.path() / "absent.xml");
    FAIL() << "no error";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.xml"), std::string::npos) << e.what();
  }
}

TEST(Sha256Test, TreeHashFollowsItsDefinition) {
  TempDir dir;
  WriteBytes(dir.path() / "fetch" / "reach.xml", "<mujoco/>");
  WriteBytes(dir.path() / "fetch" / "sub" / "a.txt", "A");
  WriteBytes(dir.path() / "stls" / "fetch" / "base.stl", std::string(300, '\x01'));
  WriteBytes(dir.path() / "ignored" / "x", "not selected");

  // the definition from the header, spelled out with sha256sum
  std::vector<std::string> records = {
      "fetch/reach.xml" + std::string(1, '\0') + Sha256sum(dir.path() / "fetch/reach.xml") + "\n",
      "fetch/sub/a.txt" + std::string(1, '\0') + Sha256sum(dir.path() / "fetch/sub/a.txt") + "\n",
      "stls/fetch/base.stl" + std::string(1, '\0') + Sha256sum(dir.path() / "stls/fetch/base.stl") +
          "\n",
  };
  std::sort(records.begin(), records.end());
  std::string joined;
  for (const auto& r : records) joined += r;

  const std::string tree = Sha256OfTree(dir.path(), {"stls", "fetch", "textures"});
  EXPECT_EQ(tree, Sha256Hex(joined));
  // order of the subfolder list does not matter; unselected folders do not count
  EXPECT_EQ(Sha256OfTree(dir.path(), {"fetch", "stls"}), tree);
  EXPECT_EQ(Sha256OfTree(dir.path(), {}), Sha256Hex(""));
  // spelling of the root and subfolders does not change the names
  EXPECT_EQ(Sha256OfTree(dir.path().string() + "/", {"./fetch", "stls/"}), tree);
  EXPECT_EQ(Sha256OfTree(dir.path() / "fetch" / "..", {"fetch", "stls/fetch"}), tree);

  // content and names both count
  WriteBytes(dir.path() / "fetch" / "sub" / "a.txt", "B");
  const std::string changed = Sha256OfTree(dir.path(), {"fetch", "stls"});
  EXPECT_NE(changed, tree);
  std::filesystem::rename(dir.path() / "fetch" / "sub" / "a.txt",
                          dir.path() / "fetch" / "sub" / "b.txt");
  EXPECT_NE(Sha256OfTree(dir.path(), {"fetch", "stls"}), changed);
}

TEST(Sha256Test, TreeHashOfGenuineAssetsIsStable) {
  const auto assets = testing::GenuineAssetsDir();
  if (assets.empty()) GTEST_SKIP() << "genuine assets not found";
  const std::string once = Sha256OfTree(assets, {"fetch", "stls", "textures"});
  EXPECT_EQ(once.size(), 64u);
  EXPECT_EQ(Sha256OfTree(assets, {"textures", "stls", "fetch"}), once);
}

}  // namespace
}  // namespace fetchscope
