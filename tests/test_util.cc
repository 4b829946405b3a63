#include "tests/test_util.h"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "dataset/hdf5_handles.h"

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

std::string FetchscopeBinary() {
  const char* other = std::getenv("FETCHSCOPE_TEST_BIN");
  return other && *other ? other : FETCHSCOPE_BIN;
}

CommandResult RunFetchscope(const std::string& args) {
  return RunCommand(FetchscopeBinary() + " " + args);
}

CommandResult RunFetchscopeStdout(const std::string& args, std::string* stderr_text) {
  char name[] = "/tmp/fetchscope-stderr-XXXXXX";
  const int fd = mkstemp(name);
  if (fd >= 0) close(fd);
  CommandResult r = RunCommand("{ " + FetchscopeBinary() + " " + args + " 2>" + name + "; }");
  if (stderr_text) *stderr_text = ReadFile(name);
  std::remove(name);
  return r;
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

std::map<std::string, std::string> AllFiles(const std::filesystem::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.is_regular_file()) files[e.path().filename().string()] = ReadFile(e.path());
  }
  return files;
}

std::set<std::string> FilesIn(const std::filesystem::path& dir) {
  std::set<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    files.insert(entry.path().filename());
  }
  return files;
}

int Count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

std::vector<std::string> LinesWith(const std::string& text, const std::string& needle) {
  std::vector<std::string> lines;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    if (line.find(needle) != std::string::npos) lines.push_back(line);
    start = end + 1;
  }
  return lines;
}

std::vector<std::string> SplitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

int LineCount(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n + (!text.empty() && text.back() != '\n');
}

pid_t SpawnFetchscope(const std::string& args, const std::filesystem::path& log) {
  const std::string command =
      "exec " + FetchscopeBinary() + " " + args + " </dev/null >" + log.string() + " 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

int ConnectLoopback(int port, int patience_s) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const timeval patience{patience_s, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &patience, sizeof(patience));
  if (connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof(addr)) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

bool SendAll(int fd, const std::string& bytes) {
  return send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(bytes.size());
}

std::string ReadUntilClosed(int fd) {
  std::string text;
  char buffer[4096];
  ssize_t n;
  while ((n = recv(fd, buffer, sizeof(buffer), 0)) > 0) text.append(buffer, n);
  return text;
}

int WaitExit(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

ServeProcess::ServeProcess(const std::string& args, const std::filesystem::path& dir)
    : log_path(dir / "serve.log") {
  const std::filesystem::path token_file = dir / "token";
  std::error_code ec;
  std::filesystem::remove(log_path, ec);  // an earlier serve's URL is not this one's
  pid = SpawnFetchscope("serve " + args + " --port 0 --token-file '" + token_file.string() + "'",
                        log_path);
  // the URL line, once the engine (GL context, environments) is up and the port bound
  for (int i = 0; i < 600; ++i) {
    const std::string text = log();
    const size_t at = text.find("serve: open ");
    if (at != std::string::npos && text.find("Ctrl-C stops it") != std::string::npos) {
      const size_t end = text.find('\n', at);
      url = text.substr(at + 12, end - at - 12);
      port = std::stoi(url.substr(url.rfind(':') + 1));
      token = ReadFile(token_file);
      while (!token.empty() && token.back() == '\n') token.pop_back();
      return;
    }
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      pid = -1;
      return;
    }
    usleep(50 * 1000);
  }
}

ServeProcess::~ServeProcess() {
  if (pid > 0) Stop(SIGINT);
}

int ServeProcess::Stop(int sig) {
  if (pid <= 0) return -1;
  kill(pid, sig);
  // a serve that ignores the signal is killed after 30 s (its status then says SIGKILL), so that
  // a test of a broken server fails instead of waiting for ever
  int status = 0;
  for (int i = 0; i < 3000; ++i) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid || (done < 0 && errno != EINTR)) {
      pid = -1;
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    usleep(10 * 1000);
  }
  kill(pid, SIGKILL);
  const int code = WaitExit(pid);
  pid = -1;
  return code;
}

std::string ServeProcess::log() const { return ReadFile(log_path); }

nlohmann::json FfprobeJson(const std::filesystem::path& path, const std::string& show_entries) {
  const CommandResult probe = RunCommand("ffprobe -v error -count_frames -show_entries " +
                                         show_entries + " -of json '" + path.string() + "'");
  EXPECT_EQ(probe.exit_code, 0) << probe.output;
  return nlohmann::json::parse(probe.output, nullptr, /*allow_exceptions=*/false);
}

std::map<std::string, std::string> FfprobeFormatTags(const std::filesystem::path& path) {
  const CommandResult probe =
      RunCommand("ffprobe -v error -show_entries format_tags -of json '" + path.string() + "'");
  EXPECT_EQ(probe.exit_code, 0) << probe.output;
  const nlohmann::json j = nlohmann::json::parse(probe.output, nullptr, false);
  std::map<std::string, std::string> tags;
  if (j.is_discarded() || !j.contains("format") || !j["format"].contains("tags")) return tags;
  for (const auto& [key, value] : j["format"]["tags"].items()) {
    std::string name = key;
    std::transform(name.begin(), name.end(), name.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    tags[name] = value.get<std::string>();
  }
  return tags;
}

bool WaitForSignalHandler(pid_t pid, int signal, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream status("/proc/" + std::to_string(pid) + "/status");
    if (!status) return false;
    std::string line;
    while (std::getline(status, line)) {
      if (line.rfind("SigCgt:", 0) != 0) continue;
      const unsigned long long caught = std::stoull(line.substr(7), nullptr, 16);
      if ((caught >> (signal - 1)) & 1ULL) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

nlohmann::json PageBlock(const std::string& html, const std::string& id) {
  const std::string open = "<script id=\"" + id + "\" type=\"application/json\">";
  const size_t begin = html.find(open);
  if (begin == std::string::npos) return nullptr;
  const size_t start = begin + open.size();
  return nlohmann::json::parse(html.substr(start, html.find("</script>", start) - start));
}

int DecodedFrames(const std::filesystem::path& video) {
  auto r = RunCommand(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=nb_read_frames -of csv=p=0 " +
      video.string());
  if (r.exit_code != 0 || r.output.empty()) return -1;
  return std::atoi(r.output.c_str());
}

std::string PythonWithH5py() {
  for (const char* py : {"python3", "/usr/bin/python3"}) {
    if (RunCommand(std::string(py) + " -c 'import h5py, numpy' 2>/dev/null").exit_code == 0) {
      return py;
    }
  }
  return "";
}

std::string PythonWithPil() {
  const std::string py = PythonWithH5py();
  if (py.empty() || RunCommand(py + " -c 'import PIL' 2>&1").exit_code != 0) return "";
  return py;
}

void WriteEdited(const std::filesystem::path& file, const std::string& text,
                 const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << file << " lacks " << from;
  std::ofstream(file, std::ios::binary) << text.substr(0, at) + to + text.substr(at + from.size());
}

void ReplaceMinariActions(const std::filesystem::path& hdf5, const std::string& episode,
                          size_t rows) {
  const H5File file(H5Fopen(hdf5.c_str(), H5F_ACC_RDWR, H5P_DEFAULT));
  ASSERT_TRUE(file.valid()) << hdf5;
  const std::string name = episode + "/actions";
  ASSERT_GE(H5Ldelete(file.get(), name.c_str(), H5P_DEFAULT), 0) << name;
  if (rows == 0) return;
  const hsize_t dims[2] = {rows, 4};
  const H5Dataspace space(H5Screate_simple(2, dims, nullptr));
  const H5Dataset dset(H5Dcreate2(file.get(), name.c_str(), H5T_IEEE_F32LE, space.get(),
                                  H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  ASSERT_TRUE(dset.valid()) << name;
  const std::vector<float> zeros(rows * 4, 0.0f);
  ASSERT_GE(H5Dwrite(dset.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, zeros.data()), 0);
}

FrameInfo ReachSuccessStep() {
  FrameInfo info;
  info.title = "FetchReach-v4";
  info.step = 7;
  info.reward = -0.0;
  info.distance = 0.012;
  info.success = true;
  info.has_action = true;
  info.action = {-0.001, 0.5, -0.25, -0.0};
  return info;
}

}  // namespace fetchscope::testing
