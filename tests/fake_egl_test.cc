// NVIDIA code paths without an NVIDIA GPU: fetchscope runs against a stand-in libEGL
// (tests/fake_egl) that advertises NVIDIA driver 580's exact strings (EGL_EXT_device_base, no
// EGL_EXT_device_enumeration; EGL_NV_device_cuda on each device; no DRM file), with devices whose
// CUDA ordinals are out of order, a device that fails to initialise, or none at all. Frames are
// real (forwarded to Mesa); the fake logs which device each process initialised.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::ReadFile;
using testing::RunCommand;
using testing::TempDir;
namespace fs = std::filesystem;

class FakeEglTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(REAL_LIBEGL)) GTEST_SKIP() << "no real libEGL to forward to";
    // Mesa's surfaceless EGL must work here for the forwarded rendering
    const CommandResult probe = RunCommand(std::string(FETCHSCOPE_BIN) + " list-gpus --json");
    if (probe.exit_code != 0) GTEST_SKIP() << "list-gpus fails here: " << probe.output;
  }

  // Runs fetchscope with the fake libEGL first on the library path. `devices` is
  // FAKE_EGL_DEVICES ("-" leaves it unset); `extra_env` more VAR=value words.
  CommandResult Run(const std::string& devices, const std::string& args,
                    const std::string& extra_env = "") {
    std::string env =
        "env -u MUJOCO_GL -u MUJOCO_EGL_DEVICE_ID -u CUDA_VISIBLE_DEVICES "
        "-u DISPLAY LD_LIBRARY_PATH=" FAKE_EGL_DIR " FAKE_EGL_REAL=" REAL_LIBEGL " FAKE_EGL_LOG=" +
        log_.string() + " ";
    if (devices != "-") env += "FAKE_EGL_DEVICES='" + devices + "' ";
    return RunCommand(env + extra_env + " " + FETCHSCOPE_BIN + " " + args);
  }

  nlohmann::json ListGpus(const std::string& devices, const std::string& extra_env = "",
                          const std::string& gpu = "") {
    const CommandResult r =
        Run(devices, "list-gpus --json" + (gpu.empty() ? "" : " --gpu " + gpu), extra_env);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return nlohmann::json::parse(r.output.substr(r.output.find('{')));
  }

  // The "pid P init device D" lines of the fake's log.
  std::vector<std::string> LogLines() {
    std::vector<std::string> lines;
    std::istringstream in(ReadFile(log_));
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  }

  // The devices initialised (successfully or not) according to the log.
  std::multiset<std::string> InitialisedDevices() {
    std::multiset<std::string> devices;
    for (const std::string& line : LogLines()) {
      devices.insert(line.substr(line.find("init device ") + 12));
    }
    return devices;
  }

  TempDir tmp_;
  fs::path log_ = tmp_.path() / "egl.log";
};

// Driver 580 advertises EGL_EXT_device_base and not EGL_EXT_device_enumeration: enumeration
// must still be used, and each device's EGL_CUDA_DEVICE_NV read.
TEST_F(FakeEglTest, NvidiaStringsEnumerateDevicesWithCudaOrdinals) {
  const nlohmann::json out = ListGpus("cuda=2,cuda=0,cuda=1");
  EXPECT_NE(out["egl"]["client_extensions"].get<std::string>().find("EGL_EXT_device_base"),
            std::string::npos);
  EXPECT_EQ(out["egl"]["client_extensions"].get<std::string>().find("EGL_EXT_device_enumeration"),
            std::string::npos);
  ASSERT_TRUE(out["egl"]["enumerable"].get<bool>()) << out.dump();
  ASSERT_EQ(out["devices"].size(), 3u);
  EXPECT_EQ(out["devices"][0]["cuda_id"], 2);
  EXPECT_EQ(out["devices"][1]["cuda_id"], 0);
  EXPECT_EQ(out["devices"][2]["cuda_id"], 1);
  EXPECT_EQ(out["devices"][0]["drm_node"], "");  // NVIDIA answers none without /dev/dri
  EXPECT_EQ(out["devices"][0]["description"], "EGL device 0 (CUDA 2)");
  // auto on NVIDIA: the first hardware device, not the surfaceless platform
  EXPECT_EQ(out["resolved"]["reason"], "auto");
}

// --gpu N and MUJOCO_EGL_DEVICE_ID name EGL devices: these failed on NVIDIA before.
TEST_F(FakeEglTest, EglIndexAndMujocoEglDeviceIdSelectThatDevice) {
  const fs::path png = tmp_.path() / "f.png";
  CommandResult r =
      Run("cuda=2,cuda=0,cuda=1",
          "render --backend egl --gpu 2 --width 32 --height 32 --verbose -o " + png.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("EGL device 2 (CUDA 1)"), std::string::npos) << r.output;
  EXPECT_EQ(InitialisedDevices(), std::multiset<std::string>{"2"});
  fs::remove(log_);
  r = Run("cuda=2,cuda=0,cuda=1", "render --backend egl --width 32 --height 32 -o " + png.string(),
          "MUJOCO_EGL_DEVICE_ID=1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(InitialisedDevices(), std::multiset<std::string>{"1"});
}

// cuda:N names the GPU CUDA calls N, whatever EGL's order.
TEST_F(FakeEglTest, CudaNumberingMapsThroughEglCudaDeviceNv) {
  const fs::path png = tmp_.path() / "f.png";
  const CommandResult r =
      Run("cuda=2,cuda=0,cuda=1",
          "render --backend egl --gpu cuda:0 --width 32 --height 32 --verbose -o " + png.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("--gpu cuda:0 = EGL device 1"), std::string::npos) << r.output;
  EXPECT_EQ(InitialisedDevices(), std::multiset<std::string>{"1"});
  const nlohmann::json out = ListGpus("cuda=2,cuda=0,cuda=1", "", "cuda:2,1");
  EXPECT_EQ(out["resolved"]["devices"], nlohmann::json({0, 2}));
  // a CUDA ordinal no device has: usage error listing the ones there are
  const CommandResult bad =
      Run("cuda=2,cuda=0,cuda=1", "render --backend egl --gpu cuda:5 -o " + png.string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("cuda:5 is not a CUDA device here; accepted CUDA ordinals: 0 (EGL 1), "
                            "1 (EGL 2), 2 (EGL 0)"),
            std::string::npos)
      << bad.output;
}

// With CUDA_VISIBLE_DEVICES set, the default is the GPU the user's CUDA program sees as 0.
// The driver numbers EGL_CUDA_DEVICE_NV after the remap, as CUDA does.
TEST_F(FakeEglTest, CudaVisibleDevicesRemapIsTheDefault) {
  const fs::path png = tmp_.path() / "f.png";
  // physical GPU 2 is EGL device 0; CUDA_VISIBLE_DEVICES=2,0 makes it CUDA 0
  CommandResult r = Run("cuda=2,cuda=0,cuda=1",
                        "render --backend egl --width 32 --height 32 --verbose -o " + png.string(),
                        "CUDA_VISIBLE_DEVICES=2,0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cuda:0 (CUDA_VISIBLE_DEVICES=2,0) = EGL device 0"), std::string::npos)
      << r.output;
  EXPECT_EQ(InitialisedDevices(), std::multiset<std::string>{"0"});
  // and cuda:1 is physical 0, EGL device 1
  const nlohmann::json out = ListGpus("cuda=2,cuda=0,cuda=1", "CUDA_VISIBLE_DEVICES=2,0", "cuda:1");
  EXPECT_EQ(out["resolved"]["devices"], nlohmann::json({1}));
  // the hidden GPU reports no ordinal
  const nlohmann::json all = ListGpus("cuda=2,cuda=0,cuda=1", "CUDA_VISIBLE_DEVICES=2,0");
  EXPECT_TRUE(all["devices"][2]["cuda_id"].is_null()) << all.dump();
}

// A device that cannot initialise: auto moves on to the next; naming it is an error that says
// why; --gpu all leaves it out with a warning.
TEST_F(FakeEglTest, DeviceThatFailsToInitialise) {
  const fs::path png = tmp_.path() / "f.png";
  CommandResult r = Run("cuda=0:fail,cuda=1",
                        "render --backend egl --width 32 --height 32 --verbose -o " + png.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("EGL device 1 (CUDA 1)"), std::string::npos) << r.output;
  fs::remove(png);
  r = Run("cuda=0:fail,cuda=1", "render --backend egl --gpu 0 -o " + png.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("EGL device 0 (CUDA 0): eglInitialize: EGL_NOT_INITIALIZED"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(png));
  const fs::path out = tmp_.path() / "run";
  r = Run("cuda=0:fail,cuda=1,cuda=2",
          "record --backend egl --gpu all --jobs 2 --episodes 2 --steps 2 --width 32 --height 32 "
          "--out " +
              out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning: EGL device 0 skipped"), std::string::npos) << r.output;
  const nlohmann::json manifest = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(manifest["gpu"]["devices"], nlohmann::json({1, 2}));
  EXPECT_EQ(manifest["workers"][0]["device"], "EGL device 1 (CUDA 1)");
  EXPECT_EQ(manifest["workers"][1]["device"], "EGL device 2 (CUDA 2)");
}

// No devices at all: auto still renders (the surfaceless platform NVIDIA lists); naming a
// device says there are none; nothing is written.
TEST_F(FakeEglTest, NoDevices) {
  const nlohmann::json out = ListGpus("");
  EXPECT_TRUE(out["egl"]["enumerable"].get<bool>());
  EXPECT_TRUE(out["devices"].empty());
  const fs::path png = tmp_.path() / "f.png";
  CommandResult r =
      Run("", "render --backend egl --width 32 --height 32 --verbose -o " + png.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("surfaceless"), std::string::npos) << r.output;
  for (const char* gpu : {"0", "all", "cuda:0"}) {
    fs::remove(png);
    r = Run("", std::string("render --backend egl --gpu ") + gpu + " -o " + png.string());
    EXPECT_EQ(r.exit_code, 1) << gpu << ": " << r.output;
    EXPECT_NE(r.output.find("enumerates none (it lists no devices)"), std::string::npos)
        << gpu << ": " << r.output;
    EXPECT_FALSE(fs::exists(png)) << gpu;
  }
  // CUDA_VISIBLE_DEVICES alone never turns "no devices" into an error
  r = Run("", "render --backend egl --width 32 --height 32 -o " + png.string(),
          "CUDA_VISIBLE_DEVICES=0");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// Worker processes spread round-robin over the devices named, each initialising its own.
TEST_F(FakeEglTest, WorkersSpreadRoundRobinOverTheChosenDevices) {
  const fs::path out = tmp_.path() / "run";
  const CommandResult r = Run("cuda=2,cuda=0,cuda=1",
                              "record --backend egl --gpu cuda:0,1 --jobs 3 --episodes 3 --steps 2 "
                              "--width 32 --height 32 --quiet --out " +
                                  out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json manifest = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  ASSERT_EQ(manifest["workers"].size(), 3u);
  EXPECT_EQ(manifest["workers"][0]["device"], "EGL device 1 (CUDA 0)");
  EXPECT_EQ(manifest["workers"][1]["device"], "EGL device 2 (CUDA 1)");
  EXPECT_EQ(manifest["workers"][2]["device"], "EGL device 1 (CUDA 0)");
  // each worker process initialised its own device (the probe also tested both once)
  std::map<std::string, std::set<std::string>> by_pid;
  for (const std::string& line : LogLines()) {
    by_pid[line.substr(4, line.find(' ', 4) - 4)].insert(line.substr(line.find("device ") + 7));
  }
  std::set<long> worker_pids;
  for (const nlohmann::json& w : manifest["workers"]) worker_pids.insert(w["pid"].get<long>());
  EXPECT_EQ(worker_pids.size(), 3u);
  std::multiset<std::string> worker_devices;
  for (long pid : worker_pids) {
    ASSERT_EQ(by_pid[std::to_string(pid)].size(), 1u) << pid;
    worker_devices.insert(*by_pid[std::to_string(pid)].begin());
  }
  EXPECT_EQ(worker_devices, (std::multiset<std::string>{"1", "1", "2"}));
}

}  // namespace
}  // namespace fetchscope
