// fetchscope: Gymnasium-Robotics Fetch episodes on MuJoCo, rendered headless.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/suggest.h"
#include "cli/command.h"
#include "cli/common.h"
#include "src/fetch_env.h"

int main(int argc, char** argv) {
  using namespace fetchscope;
  InstallMujocoHandlers();
  CLI::App app{
      "fetchscope " FETCHSCOPE_VERSION
      ": step Gymnasium-Robotics Fetch v4 episodes on MuJoCo, render them headless (EGL or "
      "OSMesa), write videos, contact sheets, trajectories and the env's anatomy JSON."};
  for (int i = 0; i < argc; ++i) cli::CommandLine() += (i ? " " : "") + std::string(argv[i]);
  app.formatter(cli::MakeHelpFormatter());  // before the subcommands: they inherit it
  app.set_version_flag("--version", FETCHSCOPE_VERSION);
  app.require_subcommand(1);
  std::vector<cli::Command> commands;
  for (cli::AddCommandFn add : cli::kCommands) commands.push_back(add(app));
  try {
    app.parse(argc, argv);
    for (const cli::Command& command : commands) {
      if (command.app->parsed()) return command.run();
    }
    return 2;  // unreachable: require_subcommand(1) made the parse fail
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // CLI11 reports a misspelt command as "A subcommand is required": name it instead
    const CLI::App* parent = &app;
    int i = 1;
    for (; i < argc && argv[i][0] != '-'; ++i) {
      const CLI::App* next = nullptr;
      for (const CLI::App* sub : parent->get_subcommands({})) {
        if (sub->get_name() == argv[i]) next = sub;
      }
      if (!next) break;
      parent = next;
    }
    if (i < argc && argv[i][0] != '-' && !parent->get_subcommands({}).empty()) {
      std::string names;
      std::vector<std::string> list;
      for (const CLI::App* sub : parent->get_subcommands({})) {
        names += (names.empty() ? "" : ", ") + sub->get_name();
        list.push_back(sub->get_name());
      }
      std::fprintf(stderr, "fetchscope: error: unknown command '%s'%s: accepted: %s\n", argv[i],
                   DidYouMean(argv[i], list).c_str(), names.c_str());
      return 2;
    }
    std::fprintf(stderr, "fetchscope: error: %s (see fetchscope --help)\n", e.what());
    return 2;
  } catch (const UsageError& e) {
    std::fprintf(stderr, "fetchscope: error: %s\n", e.what());
    return 2;
  } catch (const RunError& e) {
    std::fprintf(stderr, "fetchscope: error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fetchscope: error: %s\n", e.what());
    return 1;
  }
}
