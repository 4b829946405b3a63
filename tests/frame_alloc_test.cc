// The per-frame path of a recording, once warm, allocates nothing (a frame-sized buffer would
// cost fresh pages, page faults, every frame) and rasterises no glyph: a frame rendered with its
// HUD (Renderer::Submit/Collect), encoded (VideoWriter::AddFrame) and, every few frames, kept as a
// contact sheet tile (ScaleSheetTile). This binary replaces the global operator new to count the
// allocations made through it, and counts FreeType's glyph renders (Font::GlyphsRasterised).
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "base/errors.h"
#include "encode/contact_sheet.h"
#include "encode/video_writer.h"
#include "render/gl_context.h"
#include "render/renderer.h"
#include "render/text.h"
#include "src/mj_handles.h"
#include "tests/test_util.h"

namespace {

// An allocation at least this large is a buffer, not a string or a small node.
constexpr std::size_t kLarge = 4096;

std::atomic<long> allocations{0};
std::atomic<long> large_allocations{0};
std::atomic<long> allocated_bytes{0};

void* Counted(std::size_t size) {
  allocations.fetch_add(1, std::memory_order_relaxed);
  if (size >= kLarge) large_allocations.fetch_add(1, std::memory_order_relaxed);
  allocated_bytes.fetch_add(static_cast<long>(size), std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}

}  // namespace

// every plain and array new goes through these (the nothrow forms call them)
void* operator new(std::size_t size) { return Counted(size); }
void* operator new[](std::size_t size) { return Counted(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

constexpr int kSize = 480;
constexpr int kTileEvery = 4;

// Allocations (all, large, bytes) made by one phase of the frames recorded.
struct Tally {
  long all = 0, large = 0, bytes = 0;
};

class Counter {
 public:
  Counter() : all_(allocations), large_(large_allocations), bytes_(allocated_bytes) {}
  void Into(Tally* t) const {
    t->all += allocations - all_;
    t->large += large_allocations - large_;
    t->bytes += allocated_bytes - bytes_;
  }

 private:
  long all_, large_, bytes_;
};

class FrameAllocTest : public ::testing::Test {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    const fs::path path = testing::SourceDir() / "models" / "pick_and_place.xml";
    char error[1000] = "";
    model_.reset(mj_loadXML(path.string().c_str(), nullptr, error, sizeof(error)));
    ASSERT_TRUE(model_) << error;
    data_.reset(mj_makeData(model_.get()));
    mj_forward(model_.get(), data_.get());
    info_.title = "FetchPickAndPlace-v4";
    info_.goal = {1.4, 0.8, 0.6};
    info_.achieved = {1.3, 0.75, 0.425};
    info_.has_action = true;
    try {
      gl_ = CreateGlContext("auto");
    } catch (const RunError& e) {
      GTEST_SKIP() << "no GL context: " << e.what();
    }
  }

  // Records frames [first, first + n): each rendered with its HUD (whose numbers change from
  // frame to frame), encoded, and every kTileEvery-th kept as a sheet tile; tallies each phase.
  void Record(Renderer& renderer, VideoWriter& writer, int first, int n) {
    for (int t = first; t < first + n; ++t) {
      info_.step = t % 50;
      info_.reward = -0.001 * (t % 97);
      info_.distance = 0.01 * (t % 31);
      info_.success = t % 3 == 0;
      info_.action = {0.01 * (t % 7), -0.02 * (t % 5), 0.5, -1.0};
      const Counter render;
      renderer.Submit(data_.get(), info_, rgb_.data());
      while (renderer.pending() > 0) renderer.Collect();
      render.Into(&render_);
      const Counter encode;
      writer.AddFrame(rgb_.data());
      encode.Into(&encode_);
      if (t % kTileEvery == 0) {
        const Counter sheet;
        tiles_.push_back(
            ScaleSheetTile(rgb_.data(), kSize, kSize, "t", kSheetTileWidth, &scratch_));
        sheet.Into(&sheet_);
      }
    }
  }

  MjModelPtr model_;
  MjDataPtr data_;
  FrameInfo info_;
  std::unique_ptr<GlContext> gl_;
  std::vector<uint8_t> rgb_ = std::vector<uint8_t>(kSize * kSize * 3);
  std::vector<SheetTile> tiles_;
  SheetScratch scratch_;
  Tally render_, encode_, sheet_;
};

TEST_F(FrameAllocTest, WarmFramesAllocateNothingAndRasteriseNoGlyph) {
  RenderOptions options;
  options.width = kSize;
  options.height = kSize;
  options.overlays = ParseOverlays("default");  // the HUD and every overlay record draws
  Renderer renderer(*gl_, model_.get(), options);
  testing::TempDir dir;
  VideoOptions video;
  video.width = kSize;
  video.height = kSize;
  video.codec = "libx264";
  VideoWriter writer((dir.path() / "clip.mp4").string(), video);
  Record(renderer, writer, 0, 100);  // every digit and sign drawn once, every buffer made
  tiles_.clear();
  tiles_.reserve(100);
  render_ = encode_ = sheet_ = {};
  const long glyphs = Font::GlyphsRasterised();
  const int frames = 40;
  Record(renderer, writer, 100, frames);
  std::cout << frames << " warm frames: render + HUD " << render_.all << " allocations ("
            << render_.large << " of " << kLarge << "+ bytes, " << render_.bytes
            << " bytes); encode " << encode_.all << "; sheet tiles " << sheet_.all << " ("
            << sheet_.large << " large)\n";
  EXPECT_EQ(Font::GlyphsRasterised(), glyphs) << "glyphs rasterised again for text drawn before";
  EXPECT_EQ(render_.large, 0) << "a buffer allocated per frame by the renderer or the HUD";
  EXPECT_EQ(render_.all, 0) << "the renderer or the HUD allocates per frame (" << render_.bytes
                            << " bytes in " << frames << " frames)";
  EXPECT_EQ(encode_.all, 0) << "the encoder allocates per frame";
  // each kept tile is one buffer of its own (240x240), the scaler's working rows are reused
  EXPECT_EQ(sheet_.large, frames / kTileEvery) << "a frame-sized buffer per sheet tile";
  writer.Finish();
}

}  // namespace
}  // namespace fetchscope
