// Pixel observations in a worker (docs/guide/datasets.md, "Pixel datasets"): each step of an
// episode rendered by ObsRenderer (render/obs_view.h), compressed on the worker's own core and
// appended to the episode's staging file (dataset/pixel_obs.h), which the dataset outputs copy
// in episode order. The staging folder lives beside what is written and goes with the run.
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "base/atomic_file.h"
#include "dataset/pixel_obs.h"
#include "render/gl_context.h"
#include "render/obs_view.h"
#include "run/episode_output.h"
#include "src/episode.h"
#include "src/exec_wire.h"
#include "src/fetch_env.h"
#include "src/policy_spec.h"

namespace fetchscope {

/// What every worker renders and stages, decided by the parent.
struct PixelPlan {
  ObsSetup setup;                 ///< cameras, size, layers, overlay (none: no images)
  PixelLayout layout;             ///< what the outputs store (geometry filled as they go)
  std::filesystem::path staging;  ///< the staging folder (PixelStaging)
  /// staged for a dataset (--minari, --robomimic); else the images only go to an exec: policy
  bool to_dataset = false;
  bool enabled() const { return setup.enabled() || layout.states; }
  bool stages() const { return to_dataset && enabled(); }  ///< a staging folder is needed
};

/// The layout `setup` gives on `model`: size, layers, the cameras (names, --camera text,
/// moving), the segmentation legend of the model's bodies and sites.
PixelLayout MakePixelLayout(const ObsSetup& setup, const mjModel* model);

/// The MuJoCo state robomimic's `states` stores: time, qpos, qvel, mocap_pos, mocap_quat.
std::vector<double> FlatMujocoState(const mjModel* model, const mjData* data);
/// Its length on `model`.
size_t FlatMujocoStateSize(const mjModel* model);

/// A staging folder, `.fetchscope-pixels-<pid>-<n>` in `parent` (created if needed), removed
/// with everything in it when this goes, and `parent` too where this made it and nothing else
/// was put there (an interrupted run leaves no empty datasets folder).
class PixelStaging {
 public:
  /// Throws RunError naming the folder when it cannot be made.
  explicit PixelStaging(const std::filesystem::path& parent);
  ~PixelStaging();
  PixelStaging(const PixelStaging&) = delete;
  PixelStaging& operator=(const PixelStaging&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  ParentFolders parents_;  // the folders made for `parent`, removed again while empty
  std::filesystem::path path_;
};

/// Hands episodes on to `inner` and then removes their staging files (the last output to read
/// them), so that a long run holds on disk only the episodes not yet written.
class StagingConsumer : public EpisodeOutput {
 public:
  StagingConsumer(EpisodeOutput& inner, std::filesystem::path staging)
      : inner_(inner), staging_(std::move(staging)) {}
  void Begin(const OutputRun& run) override { inner_.Begin(run); }
  void Add(const EpisodeRecord& episode) override;
  std::string Finish() override { return inner_.Finish(); }
  void Abort() override { inner_.Abort(); }
  void SetSelection(const nlohmann::json& selection) override { inner_.SetSelection(selection); }

 private:
  EpisodeOutput& inner_;
  std::filesystem::path staging_;
};

/// One worker's pixel observations: its renderer (made on the worker's GL context) and the
/// staging file of the episode in hand (none when the plan does not stage: the images then only
/// go to an exec: policy). The render thread draws each step; a thread of the
/// recorder's own compresses and writes the images in order (PNG, gzip, the staging file), so
/// that drawing and compressing overlap as record's drawing and encoding do.
class PixelRecorder {
 public:
  /// `gl` (current on this thread; null when no camera is observed) and `model` outlive the
  /// recorder. Throws UsageError as
  /// Renderer does.
  PixelRecorder(const PixelPlan& plan, GlContext* gl, mjModel* model);
  ~PixelRecorder();

  /// Opens episode `index`'s staging file (replacing one a failed try left).
  void Begin(int index);
  /// Renders and stages the images of `env`'s current state, step `record.t`.
  void Step(const FetchEnv& env, const StepRecord& record);
  /// Waits until the episode's staging file is written and closed. Throws RunError where it
  /// could not be written (also from Step, once a write failed).
  void End();
  /// Draws the images of later Steps with `look` (ObsRenderer::SetLook; nullptr: plain).
  void SetLook(const LookDraw* look) {
    if (renderer_) renderer_->SetLook(look);
  }
  /// The observed cameras' keys (ObsRenderer::camera_keys), for DrawLook; none without cameras.
  std::vector<std::string> camera_keys() const {
    return renderer_ ? renderer_->camera_keys() : std::vector<std::string>{};
  }
  /// The images of the last Step as an exec: policy receives them; null without cameras.
  /// Made when first asked after a Step (a dataset run without an exec: policy never asks).
  const WireStep* wire();

 private:
  // One unit of the writing thread's work, in order.
  struct Job {
    enum Kind { kOpen, kStep, kClose } kind = kStep;
    int index = 0;                  // kOpen: the episode
    int t = 0;                      // kStep: the step
    std::vector<ObsImages> images;  // kStep: each camera's images
    std::vector<double> state;      // kStep: the MuJoCo state (layout.states)
  };
  void Push(Job job);
  void Write(const Job& job);  // on the writing thread
  void Loop();
  void RethrowError();

  void UpdateWire(int t);  // wire_ from the renderer's images of step t

  const PixelPlan& plan_;
  std::optional<ObsRenderer> renderer_;
  WireStep wire_;                               // points into renderer_'s images
  int drawn_t_ = -1;                            // the step renderer_'s images show
  uint64_t draws_ = 0, wired_ = 0;              // Steps drawn; the draw wire_ describes
  std::unique_ptr<PixelStagingWriter> writer_;  // the writing thread's
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Job> queue_;
  bool busy_ = false;  // the writing thread holds a job
  bool quit_ = false;
  std::exception_ptr error_;
  std::thread thread_;  // last: started once the rest is made
};

/// `base` with the images of `*pixels` for an exec: policy (PixelRecorder::wire), read when the
/// policy asks: the recorder may be made after the policy.
PolicyContext WithImages(const PolicyContext& base, std::optional<PixelRecorder>* pixels);

}  // namespace fetchscope
