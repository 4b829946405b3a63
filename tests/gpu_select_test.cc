// --gpu as a user writes it, matched against device lists as the drivers report them: NVIDIA's
// (CUDA ordinals through EGL_NV_device_cuda, in an order of its own) and Mesa's (no CUDA
// ordinals, a software device). No EGL is loaded: the lists are built here.
#include "render/gpu_select.h"

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "base/errors.h"

namespace fetchscope {
namespace {

using Kind = GpuSpec::Kind;

// Three NVIDIA GPUs whose EGL order differs from CUDA's: EGL 0 is CUDA 2, EGL 1 is CUDA 0,
// EGL 2 is CUDA 1.
EglDeviceList NvidiaNode() {
  EglDeviceList list;
  list.enumerable = true;
  const int cuda[] = {2, 0, 1};
  for (int i = 0; i < 3; ++i) {
    EglDevice d;
    d.index = i;
    d.cuda_id = cuda[i];
    d.extensions = "EGL_NV_device_cuda EGL_EXT_device_drm EGL_EXT_device_drm_render_node";
    list.devices.push_back(d);
  }
  return list;
}

// Mesa on a machine with one GPU: a DRM device and llvmpipe's software device, no CUDA ordinals.
EglDeviceList MesaMachine() {
  EglDeviceList list;
  list.enumerable = true;
  EglDevice gpu;
  gpu.index = 0;
  gpu.drm_node = "/dev/dri/card0";
  EglDevice soft;
  soft.index = 1;
  soft.software = true;
  list.devices = {gpu, soft};
  return list;
}

std::string UsageMessage(const std::string& text) {
  try {
    ParseGpuSpec(text);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

TEST(GpuSpec, ParsesEveryAcceptedForm) {
  EXPECT_EQ(ParseGpuSpec("").kind, Kind::kAuto);
  EXPECT_EQ(ParseGpuSpec("auto").kind, Kind::kAuto);
  EXPECT_EQ(ParseGpuSpec("all").kind, Kind::kAll);
  const GpuSpec one = ParseGpuSpec("1");
  EXPECT_EQ(one.kind, Kind::kEgl);
  EXPECT_EQ(one.ids, std::vector<int>{1});
  const GpuSpec list = ParseGpuSpec("0,2");
  EXPECT_EQ(list.kind, Kind::kEgl);
  EXPECT_EQ(list.ids, (std::vector<int>{0, 2}));
  EXPECT_EQ(ParseGpuSpec("2, 0").ids, (std::vector<int>{2, 0}));  // order kept, spaces allowed
  const GpuSpec cuda = ParseGpuSpec("cuda:2,1");
  EXPECT_EQ(cuda.kind, Kind::kCuda);
  EXPECT_EQ(cuda.ids, (std::vector<int>{2, 1}));
}

TEST(GpuSpec, BadValuesAreNamedWithTheAcceptedForms) {
  for (const std::string bad :
       {"-7", "cuda:", "cuda:x", "gpu0", "0,,1", "1,1", "cuda:0,0", "1.5", "99999", "ALL"}) {
    const std::string message = UsageMessage(bad);
    ASSERT_FALSE(message.empty()) << "accepted '" << bad << "'";
    EXPECT_NE(message.find("--gpu '" + bad + "'"), std::string::npos) << message;
    EXPECT_NE(message.find("cuda:N"), std::string::npos) << message;
  }
}

TEST(GpuSpec, FlagThenMujocoEglDeviceIdThenCudaVisibleDevices) {
  std::map<std::string, std::string> env;
  const EnvLookup lookup = [&](const char* name) -> const char* {
    auto it = env.find(name);
    return it == env.end() ? nullptr : it->second.c_str();
  };
  EXPECT_EQ(EffectiveGpuSpec("", lookup).kind, Kind::kAuto);

  env["CUDA_VISIBLE_DEVICES"] = "3,1";
  GpuSpec spec = EffectiveGpuSpec("", lookup);
  EXPECT_EQ(spec.kind, Kind::kCuda);
  EXPECT_EQ(spec.ids, std::vector<int>{0});  // the first visible GPU, as CUDA numbers it
  EXPECT_TRUE(spec.soft);
  EXPECT_EQ(spec.source, "CUDA_VISIBLE_DEVICES");

  env["MUJOCO_EGL_DEVICE_ID"] = "2";
  spec = EffectiveGpuSpec("", lookup);
  EXPECT_EQ(spec.kind, Kind::kEgl);
  EXPECT_EQ(spec.ids, std::vector<int>{2});
  EXPECT_EQ(spec.source, "MUJOCO_EGL_DEVICE_ID");

  spec = EffectiveGpuSpec("cuda:1", lookup);
  EXPECT_EQ(spec.kind, Kind::kCuda);
  EXPECT_EQ(spec.ids, std::vector<int>{1});
  EXPECT_FALSE(spec.soft);

  env["MUJOCO_EGL_DEVICE_ID"] = "first";
  try {
    EffectiveGpuSpec("", lookup);
    ADD_FAILURE() << "MUJOCO_EGL_DEVICE_ID=first accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("MUJOCO_EGL_DEVICE_ID 'first'"), std::string::npos)
        << e.what();
  }
}

TEST(GpuChoice, EglIndicesListsAndAllOnAnNvidiaNode) {
  const EglDeviceList node = NvidiaNode();
  EXPECT_EQ(ChooseGpus(ParseGpuSpec("2"), node).devices, std::vector<int>{2});
  EXPECT_EQ(ChooseGpus(ParseGpuSpec("0,2"), node).devices, (std::vector<int>{0, 2}));
  EXPECT_EQ(ChooseGpus(ParseGpuSpec("all"), node).devices, (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(ChooseGpus(ParseGpuSpec("auto"), node).devices.empty());
  try {
    ChooseGpus(ParseGpuSpec("0,3"), node);
    ADD_FAILURE() << "--gpu 0,3 accepted with 3 devices";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("3 is out of range; accepted: 0..2"), std::string::npos)
        << e.what();
  }
}

TEST(GpuChoice, CudaNumberingMapsThroughTheDevicesCudaOrdinals) {
  const EglDeviceList node = NvidiaNode();
  EXPECT_EQ(ChooseGpus(ParseGpuSpec("cuda:0"), node).devices, std::vector<int>{1});
  EXPECT_EQ(ChooseGpus(ParseGpuSpec("cuda:2,1"), node).devices, (std::vector<int>{0, 2}));
  const GpuChoice choice = ChooseGpus(ParseGpuSpec("cuda:1"), node);
  EXPECT_EQ(choice.devices, std::vector<int>{2});
  EXPECT_NE(choice.reason.find("EGL device 2"), std::string::npos) << choice.reason;
  try {
    ChooseGpus(ParseGpuSpec("cuda:3"), node);
    ADD_FAILURE() << "cuda:3 accepted with CUDA ordinals 0..2";
  } catch (const UsageError& e) {
    // the message lists the ordinals there are, with their EGL indices
    EXPECT_NE(std::string(e.what()).find("0 (EGL 1), 1 (EGL 2), 2 (EGL 0)"), std::string::npos)
        << e.what();
  }
}

TEST(GpuChoice, CudaVisibleDevicesFollowsCudaWhereItCanAndFallsBackWhereItCannot) {
  const EnvLookup visible = [](const char* name) -> const char* {
    return std::string(name) == "CUDA_VISIBLE_DEVICES" ? "2" : nullptr;
  };
  const GpuSpec soft = EffectiveGpuSpec("", visible);
  // NVIDIA: CUDA_VISIBLE_DEVICES=2 leaves one GPU, which CUDA calls 0 and reports so on its
  // EGL device (the driver applies the remap to EGL_CUDA_DEVICE_NV too)
  EglDeviceList remapped = NvidiaNode();
  for (EglDevice& d : remapped.devices) d.cuda_id = d.index == 0 ? 0 : -1;
  EXPECT_EQ(ChooseGpus(soft, remapped).devices, std::vector<int>{0});
  // Mesa reports no CUDA ordinals: the soft default renders as auto, and says why
  const GpuChoice mesa = ChooseGpus(soft, MesaMachine());
  EXPECT_TRUE(mesa.devices.empty());
  EXPECT_NE(mesa.reason.find("auto"), std::string::npos) << mesa.reason;
  // an explicit cuda:0 on Mesa is an error that says what to do instead
  try {
    ChooseGpus(ParseGpuSpec("cuda:0"), MesaMachine());
    ADD_FAILURE() << "cuda:0 accepted on an EGL without CUDA ordinals";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("list-gpus"), std::string::npos) << e.what();
  }
}

TEST(GpuChoice, AllSkipsTheSoftwareDeviceUnlessItIsTheOnlyOne) {
  EXPECT_EQ(ChooseGpus(ParseGpuSpec("all"), MesaMachine()).devices, std::vector<int>{0});
  EglDeviceList software_only;
  software_only.enumerable = true;
  EglDevice soft;
  soft.software = true;
  software_only.devices = {soft};
  EXPECT_EQ(ChooseGpus(ParseGpuSpec("all"), software_only).devices, std::vector<int>{0});
}

TEST(GpuChoice, AnEglWithoutEnumerationRefusesADeviceRequest) {
  EglDeviceList none;
  none.enumerable = false;
  none.why_not = "EGL_EXT_platform_device missing";
  try {
    ChooseGpus(ParseGpuSpec("0"), none);
    ADD_FAILURE() << "--gpu 0 accepted without enumeration";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("EGL_EXT_platform_device missing"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(ChooseGpus(ParseGpuSpec("auto"), none).devices.empty());
}

}  // namespace
}  // namespace fetchscope
