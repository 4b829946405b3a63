#include "tests/test_util.h"

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

namespace fetchscope::testing {

CommandResult RunCommand(const std::string& command) {
  CommandResult result{-1, ""};
  std::string full = command + " 2>&1";
  FILE* pipe = popen(full.c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) result.output.append(buf.data(), n);
  int status = pclose(pipe);
  if (WIFEXITED(status)) {
    result.exit_code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    result.exit_code = 128 + WTERMSIG(status);
  }
  return result;
}

CommandResult RunFetchscope(const std::string& args) {
  return RunCommand(std::string(FETCHSCOPE_BIN) + " " + args);
}

TempDir::TempDir() {
  std::random_device rd;
  for (int i = 0; i < 100; ++i) {
    auto p = std::filesystem::temp_directory_path() /
             ("fetchscope_test_" + std::to_string(rd()) + "_" + std::to_string(i));
    if (std::filesystem::create_directory(p)) {
      path_ = p;
      return;
    }
  }
  std::abort();
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

std::filesystem::path GenuineAssetsDir() {
  std::filesystem::path p =
      std::filesystem::path(FETCHSCOPE_SHARED_DIR) / "gymnasium-robotics-assets";
  if (std::filesystem::exists(p / "fetch" / "reach.xml")) return std::filesystem::canonical(p);
  return {};
}

std::filesystem::path SourceDir() { return FETCHSCOPE_SOURCE_DIR; }

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::map<std::string, std::string> EpisodeFiles(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("episode_", 0) == 0) files[name] = ReadFile(e.path());
  }
  return files;
}

pid_t SpawnFetchscope(const std::string& args, const std::filesystem::path& log) {
  const std::string command =
      "exec " + std::string(FETCHSCOPE_BIN) + " " + args + " </dev/null >" + log.string() + " 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

int WaitExit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string PythonWithH5py() {
  for (const char* py : {"python3", "/usr/bin/python3"}) {
    if (RunCommand(std::string(py) + " -c 'import h5py, numpy' 2>/dev/null").exit_code == 0) {
      return py;
    }
  }
  return "";
}

}  // namespace fetchscope::testing
