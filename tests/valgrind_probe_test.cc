// tools/valgrind-probe.sh: tells a program valgrind cannot run on this host (CI's valgrind
// stage then says so in one line and goes on) from one it can, checked against what valgrind
// itself does with a program that executes RDTSCP before main, as libhwy does. On a host whose
// CPU hides RDTSCP (some AMD EPYC machines) this is the very failure that stopped CI there.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/test_util.h"

namespace fetchscope::testing {
namespace {

const std::string kProbe = SourceDir().string() + "/tools/valgrind-probe.sh";

bool HaveValgrind() { return RunCommand("command -v valgrind").exit_code == 0; }

TEST(ValgrindProbe, AgreesWithValgrindOnAProgramThatExecutesRdtscpBeforeMain) {
  if (!HaveValgrind()) GTEST_SKIP() << "valgrind is not installed";
  const std::string program = RDTSCP_PROBE;
  const CommandResult native = RunCommand(program);
  if (native.exit_code != 0) GTEST_SKIP() << "this CPU does not execute RDTSCP natively";
  // what valgrind itself makes of it
  const CommandResult direct = RunCommand("valgrind --tool=none " + program);
  const bool decodes =
      direct.output.find("unhandled instruction bytes: 0xF 0x1 0xF9") == std::string::npos;
  EXPECT_EQ(decodes, direct.exit_code == 0) << direct.output;
  std::cout << "valgrind " << (decodes ? "decodes" : "cannot decode") << " RDTSCP on this host\n";

  const CommandResult probe = RunCommand(kProbe + " " + program);
  if (decodes) {
    EXPECT_EQ(probe.exit_code, 0) << probe.output;
    EXPECT_EQ(probe.output, "");
  } else {
    EXPECT_EQ(probe.exit_code, 3) << probe.output;
    EXPECT_EQ(LineCount(probe.output), 1) << probe.output;
    EXPECT_NE(probe.output.find("cannot run rdtscp_probe on this host"), std::string::npos)
        << probe.output;
    EXPECT_NE(probe.output.find("RDTSCP (0xF 0x1 0xF9)"), std::string::npos) << probe.output;
    EXPECT_NE(probe.output.find("ReadCounterTwice"), std::string::npos) << probe.output;
  }
}

TEST(ValgrindProbe, FetchscopeIsJudgedByWhetherItsLibhwyCanRunUnderValgrind) {
  if (!HaveValgrind()) GTEST_SKIP() << "valgrind is not installed";
  const bool loads_hwy =
      RunCommand("ldd " + std::string(FETCHSCOPE_BIN) + " | grep -q libhwy").exit_code == 0;
  const CommandResult direct =
      RunCommand(std::string("valgrind --tool=none ") + FETCHSCOPE_BIN + " --version");
  const bool runs = direct.exit_code == 0;
  const CommandResult probe = RunCommand(kProbe + " " + FETCHSCOPE_BIN + " --version");
  EXPECT_EQ(probe.exit_code, runs ? 0 : 3) << probe.output << direct.output;
  if (!runs) {
    EXPECT_EQ(LineCount(probe.output), 1) << probe.output;
    EXPECT_NE(probe.output.find("cannot run fetchscope on this host"), std::string::npos);
    // where libhwy is what stops it, the line names it
    if (loads_hwy && direct.output.find("hwy::") != std::string::npos) {
      EXPECT_NE(probe.output.find("hwy::platform::TimerResolution"), std::string::npos)
          << probe.output;
    }
  }
}

TEST(ValgrindProbe, AProgramThatFailsOnItsOwnIsNotValgrindsFailure) {
  if (!HaveValgrind()) GTEST_SKIP() << "valgrind is not installed";
  const CommandResult probe = RunCommand(kProbe + " /bin/false");
  EXPECT_EQ(probe.exit_code, 0) << probe.output;
  const CommandResult missing = RunCommand(kProbe + " /nonexistent/program");
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("no program '/nonexistent/program'"), std::string::npos);
}

// The test binaries CI's valgrind stage checks with memcheck on every host load no libavcodec
// (and so no libhwy): tests are linked --as-needed.
TEST(ValgrindProbe, CoreTestBinariesLoadNoLibavcodec) {
  const std::string dir = (std::filesystem::path(FETCHSCOPE_BIN).parent_path() / "tests").string();
  for (const char* name :
       {"fetch_env_test", "rng_test", "trajectory_test", "scripted_policy_test", "msaa_test"}) {
    const CommandResult ldd = RunCommand("ldd " + dir + "/" + name);
    ASSERT_EQ(ldd.exit_code, 0) << name << ": " << ldd.output;
    EXPECT_EQ(ldd.output.find("libavcodec"), std::string::npos) << name;
    // the environment's tests do load MuJoCo (the generator's alone does not need it)
    if (std::string(name) != "rng_test") {
      EXPECT_NE(ldd.output.find("libmujoco"), std::string::npos) << name;
    }
  }
}

}  // namespace
}  // namespace fetchscope::testing
