// fetchscope: Gymnasium-Robotics Fetch episodes on MuJoCo, rendered headless.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>

#include "cli/common.h"
#include "src/errors.h"
#include "src/fetch_env.h"

int main(int argc, char** argv) {
  using namespace fetchscope;
  InstallMujocoHandlers();
  CLI::App app{
      "fetchscope " FETCHSCOPE_VERSION
      ": step Gymnasium-Robotics Fetch v4 episodes on MuJoCo, render them headless (EGL or "
      "OSMesa), write videos, contact sheets, trajectories and the env's anatomy JSON."};
  for (int i = 0; i < argc; ++i) cli::CommandLine() += (i ? " " : "") + std::string(argv[i]);
  app.set_version_flag("--version", FETCHSCOPE_VERSION);
  app.require_subcommand(1);
  cli::RegisterListEnvs(app);
  cli::RegisterDescribe(app);
  cli::RegisterRewardCheck(app);
  cli::RegisterRandomEpisodes(app);
  cli::RegisterRollout(app);
  cli::RegisterRender(app);
  cli::RegisterListCameras(app);
  cli::RegisterRecord(app);
  cli::RegisterBench(app);
  cli::RegisterProbeActions(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
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
  return cli::ExitStatus();
}
