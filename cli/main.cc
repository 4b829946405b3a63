// fetchscope: Gymnasium-Robotics Fetch episodes on MuJoCo, rendered headless.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "base/errors.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/parse_errors.h"
#include "render/gl_context.h"
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
    ResolveWindowedMujocoGl();  // after parsing: --help and usage errors stay quiet
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
    std::fprintf(stderr, "fetchscope: error: %s\n",
                 cli::ParseErrorMessage(app, e, argc, argv).c_str());
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
