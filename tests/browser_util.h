// What the browser tests share (tests/browser_test.cc, tests/browser_serve_test.cc): Debian's
// chromium driven by playwright-core from web/node_modules, skipped when either is absent, and
// the screenshot each test attaches (tests/CMakeLists.txt gives build/test-screenshots/<test>.png
// to ctest as ATTACHED_FILES).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/test_util.h"

namespace fetchscope::testing {

/// The chromium the tests drive: $FETCHSCOPE_CHROMIUM, else Debian's.
inline std::string Chromium() {
  const char* env = std::getenv("FETCHSCOPE_CHROMIUM");
  return env && *env ? env : "/usr/bin/chromium";
}

/// Why the browser tests cannot run here, or empty when they can.
inline std::string MissingTool() {
  if (RunCommand("command -v node").exit_code != 0) return "node is not installed";
  if (!std::filesystem::exists(Chromium())) return "chromium is not installed (" + Chromium() + ")";
  if (!std::filesystem::exists(SourceDir() / "web" / "node_modules" / "playwright-core" /
                               "package.json")) {
    return "playwright-core is not installed in web/node_modules (tools/install-deps.sh)";
  }
  return "";
}

/// build/test-screenshots/<name of the running test>.png: the path tests/CMakeLists.txt attaches.
inline std::filesystem::path ScreenshotPath() {
  const std::filesystem::path dir =
      std::filesystem::path(FETCHSCOPE_BIN).parent_path() / "test-screenshots";
  std::filesystem::create_directories(dir);
  return dir /
         (std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".png");
}

/// The JSON of a file.
inline nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  return nlohmann::json::parse(ReadFile(path));
}

/// The JSON object a check script (web/test/*.mjs) printed last on its output; discarded (not an
/// object) when there is none.
inline nlohmann::json LastJson(const std::string& output) {
  const size_t line = output.rfind("\n{");
  return nlohmann::json::parse(output.substr(line == std::string::npos ? 0 : line + 1), nullptr,
                               /*allow_exceptions=*/false);
}

/// A browser test: skipped without node, chromium or playwright-core; no stale screenshot.
class BrowserTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::remove(ScreenshotPath());  // a skipped or failed test attaches none
    const std::string missing = MissingTool();
    if (!missing.empty()) GTEST_SKIP() << missing;
  }
};

}  // namespace fetchscope::testing
