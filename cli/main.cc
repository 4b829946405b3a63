// fetchscope: Gymnasium-Robotics Fetch episodes on MuJoCo, rendered headless.
#include <fcntl.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/process.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/parse_errors.h"
#include "render/gl_context.h"
#include "src/fetch_env.h"

namespace {

// Standard output is an output like any file: a full disk or a closed pipe under a redirection
// must not pass as success (what coreutils' close_stdout does). Returns the exit code to use.
int FinishStdout(int code) {
  errno = 0;
  std::cout.flush();
  bool failed = !std::cout || std::fflush(stdout) != 0 || std::ferror(stdout);
  int reason = errno;
  if (failed && reason == 0) {  // an earlier write failed: errno is gone, the disk may be full
    struct statvfs st {};
    if (fcntl(STDOUT_FILENO, F_GETFD) == -1) {
      reason = EBADF;  // stdout closed (>&-)
    } else if (write(STDOUT_FILENO, "", 0) < 0) {
      reason = errno;  // a device that refuses every write (/dev/full: ENOSPC); writes nothing
    } else {
      reason = fstatvfs(STDOUT_FILENO, &st) == 0 && st.f_bavail == 0 ? ENOSPC : EIO;
    }
  }
  // a stdout the caller closed (>&-) that we never wrote to is no failure
  if (std::fclose(stdout) != 0 && !failed && errno != EBADF) {
    failed = true;
    reason = errno;
  }
  if (!failed) return code;
  std::fprintf(stderr, "fetchscope: error: cannot write to standard output: %s\n",
               std::strerror(reason));
  return code == 0 ? 1 : code;
}

int Run(int argc, char** argv) {
  using namespace fetchscope;
  InstallMujocoHandlers();
  CLI::App app{
      "fetchscope " FETCHSCOPE_VERSION
      ": step Gymnasium-Robotics Fetch v4 episodes on MuJoCo, render them headless (EGL or "
      "OSMesa), write videos, contact sheets, trajectories and the env's anatomy JSON."};
  // as a shell reads it back: the manifests' command_line and the commands we print paste
  for (int i = 0; i < argc; ++i) cli::CommandLine() += (i ? " " : "") + ShellQuote(argv[i]);
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

}  // namespace

int main(int argc, char** argv) { return FinishStdout(Run(argc, argv)); }
