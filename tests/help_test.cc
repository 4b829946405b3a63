// --help of every command reads as prose: no CLI11 type artefacts ("--seed TEXT=0",
// "--no-peers{false}", "INT in [1 - 50]").
#include <gtest/gtest.h>

#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::RunFetchscope;

// The subcommands listed under "Subcommands:" of `fetchscope [SUB] --help`.
std::vector<std::string> Subcommands(const std::string& help) {
  std::vector<std::string> names;
  std::istringstream in(help.substr(
      help.find("Subcommands:") == std::string::npos ? help.size() : help.find("Subcommands:")));
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_match(line, m, std::regex("  ([a-z][a-z-]*)\\s.*"))) names.push_back(m[1]);
  }
  return names;
}

void ExpectCleanHelp(const std::string& command) {
  const auto r = RunFetchscope(command + " --help");
  SCOPED_TRACE(command + " --help:\n" + r.output);
  ASSERT_EQ(r.exit_code, 0);
  for (const char* artefact : {"{false}", "{true}", "Env:", "Needs:", "Excludes:"}) {
    EXPECT_EQ(r.output.find(artefact), std::string::npos) << "artefact '" << artefact << "'";
  }
  // CLI11's type names as words (SIGINT in prose is fine)
  std::smatch m;
  EXPECT_FALSE(std::regex_search(r.output, m, std::regex("\\b(TEXT|INT|UINT|FLOAT|BOOLEAN)\\b")))
      << "artefact '" << m.str() << "'";
  // a value placeholder is never glued to a default ("SEED=0")
  EXPECT_FALSE(std::regex_search(r.output, std::regex("--[a-z-]+ [A-Z_]+=")));
}

TEST(Help, EveryCommandHasNoCli11Artefacts) {
  ExpectCleanHelp("");
  const auto top = RunFetchscope("--help");
  const std::vector<std::string> subs = Subcommands(top.output);
  ASSERT_GE(subs.size(), 14u) << top.output;
  for (const std::string& sub : subs) {
    ExpectCleanHelp(sub);
    const auto r = RunFetchscope(sub + " --help");
    for (const std::string& nested : Subcommands(r.output)) ExpectCleanHelp(sub + " " + nested);
  }
}

TEST(Help, PlaceholdersAndDefaultsReadAsProse) {
  const auto r = RunFetchscope("random-episodes --help");
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("--seed SEED"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(default: 0)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--n-episodes N_EPISODES"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("ddof=0"), std::string::npos) << r.output;
  const auto bench = RunFetchscope("bench --help");
  EXPECT_NE(bench.output.find("--no-peers "), std::string::npos) << bench.output;
  const auto render = RunFetchscope("render --help");
  EXPECT_NE(render.output.find("(required)"), std::string::npos) << render.output;
}

}  // namespace
}  // namespace fetchscope
