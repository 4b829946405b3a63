#include "run/pixel_recorder.h"

#include <unistd.h>

#include <atomic>
#include <system_error>

#include "base/errors.h"
#include "encode/png_io.h"
#include "render/view.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

ImageLayer ToImageLayer(Layer layer) {
  switch (layer) {
    case Layer::kRgb:
      return ImageLayer::kRgb;
    case Layer::kDepth:
      return ImageLayer::kDepth;
    case Layer::kSegmentation:
      return ImageLayer::kSegmentation;
  }
  return ImageLayer::kRgb;
}

std::string NameOf(const mjModel* model, int type, int id) {
  const char* name = mj_id2name(model, type, id);
  return name ? std::string(name) : std::string(mju_type2Str(type)) + " " + std::to_string(id);
}

}  // namespace

PixelLayout MakePixelLayout(const ObsSetup& setup, const mjModel* model) {
  PixelLayout layout;
  layout.width = setup.width;
  layout.height = setup.height;
  for (Layer l : setup.layers) layout.layers.push_back(ToImageLayer(l));
  for (const ObsCamera& c : setup.cameras) {
    PixelCamera camera;
    camera.name = c.name;
    camera.camera = c.text;
    camera.moving = c.moving;
    layout.cameras.push_back(camera);
  }
  std::vector<std::string> bodies;
  for (int i = 0; i < model->nbody; ++i) bodies.push_back(NameOf(model, mjOBJ_BODY, i));
  std::vector<std::pair<std::string, std::string>> sites;
  for (int i = 0; i < model->nsite; ++i) {
    sites.emplace_back(NameOf(model, mjOBJ_BODY, model->site_bodyid[i]),
                       NameOf(model, mjOBJ_SITE, i));
  }
  layout.segmentation_legend = SegmentationLegend(bodies, sites);
  layout.overlay = setup.overlay_text;
  return layout;
}

size_t FlatMujocoStateSize(const mjModel* model) {
  return 1 + static_cast<size_t>(model->nq) + model->nv + 7 * static_cast<size_t>(model->nmocap);
}

std::vector<double> FlatMujocoState(const mjModel* model, const mjData* data) {
  std::vector<double> s;
  s.reserve(FlatMujocoStateSize(model));
  s.push_back(data->time);
  s.insert(s.end(), data->qpos, data->qpos + model->nq);
  s.insert(s.end(), data->qvel, data->qvel + model->nv);
  s.insert(s.end(), data->mocap_pos, data->mocap_pos + 3 * model->nmocap);
  s.insert(s.end(), data->mocap_quat, data->mocap_quat + 4 * model->nmocap);
  return s;
}

PixelStaging::PixelStaging(const fs::path& parent)
    : parents_((parent / ".fetchscope-pixels").string()) {
  static std::atomic<int> counter{0};
  std::error_code ec;
  path_ =
      parent / (".fetchscope-pixels-" + std::to_string(getpid()) + "-" + std::to_string(counter++));
  bool made = fs::create_directory(path_, ec) && !ec;
  // another writer on the same root may remove an empty folder it made meanwhile: made again
  for (int attempt = 0; !made && ec == std::errc::no_such_file_or_directory && attempt < 8;
       ++attempt) {
    parents_ = ParentFolders((parent / ".fetchscope-pixels").string());
    made = fs::create_directory(path_, ec) && !ec;
  }
  if (!made) {
    const std::string why = ec ? ec.message() : "it exists";
    path_.clear();
    throw RunError("cannot make the image staging folder in '" + parent.string() + "': " + why);
  }
}

PixelStaging::~PixelStaging() {
  std::error_code ec;
  if (!path_.empty()) fs::remove_all(path_, ec);
}

void StagingConsumer::Add(const EpisodeRecord& episode) {
  inner_.Add(episode);
  std::error_code ec;
  fs::remove(StagingFileOf(staging_, episode.index), ec);
}

PolicyContext WithImages(const PolicyContext& base, std::optional<PixelRecorder>* pixels) {
  PolicyContext context = base;
  context.images = [pixels](int) -> const WireStep* {
    return *pixels ? (*pixels)->wire() : nullptr;
  };
  return context;
}

PixelRecorder::PixelRecorder(const PixelPlan& plan, GlContext* gl, mjModel* model) : plan_(plan) {
  if (plan_.setup.enabled()) {
    renderer_.emplace(*gl, model, plan_.setup);
    if (plan_.setup.has(Layer::kSegmentation)) wire_.legend = plan_.layout.segmentation_legend;
  }
  if (plan_.stages()) thread_ = std::thread([this] { Loop(); });
}

PixelRecorder::~PixelRecorder() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    quit_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

// Steps queued ahead of the writing thread at most: a few frames' images, not an episode's.
constexpr size_t kMaxQueued = 8;

void PixelRecorder::Push(Job job) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return queue_.size() < kMaxQueued || error_; });
  if (error_) return;  // End (or the next Step) reports it
  queue_.push_back(std::move(job));
  changed_.notify_all();
}

void PixelRecorder::RethrowError() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!error_) return;
  std::exception_ptr e = error_;
  error_ = nullptr;
  std::rethrow_exception(e);
}

void PixelRecorder::Loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    changed_.wait(lock, [&] { return quit_ || !queue_.empty(); });
    if (queue_.empty()) return;  // quit, nothing left
    Job job = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    const bool skip = error_ != nullptr;  // after a failed write: drop the episode's rest
    lock.unlock();
    std::exception_ptr failed;
    if (!skip || job.kind == Job::kOpen) {
      try {
        Write(job);
      } catch (...) {
        failed = std::current_exception();
        writer_.reset();
      }
    }
    lock.lock();
    busy_ = false;
    if (failed) error_ = failed;
    changed_.notify_all();
  }
}

void PixelRecorder::Begin(int index) {
  if (!plan_.stages()) return;
  RethrowError();
  Job job;
  job.kind = Job::kOpen;
  job.index = index;
  Push(std::move(job));
}

void PixelRecorder::Step(const FetchEnv& env, const StepRecord& record) {
  RethrowError();
  Job job;
  job.t = record.t;
  if (plan_.layout.states) job.state = FlatMujocoState(env.model(), env.data());
  if (renderer_) {
    renderer_->Render(env.data(), MakeFrameInfo(env, record));
    drawn_t_ = record.t;
    ++draws_;
    if (!plan_.stages()) return;
    for (size_t c = 0; c < renderer_->cameras(); ++c) job.images.push_back(renderer_->images(c));
  }
  if (plan_.stages()) Push(std::move(job));
}

const WireStep* PixelRecorder::wire() {
  if (!renderer_) return nullptr;
  if (wired_ != draws_) {
    UpdateWire(drawn_t_);
    wired_ = draws_;
  }
  return &wire_;
}

void PixelRecorder::UpdateWire(int t) {
  const ObsSetup& setup = plan_.setup;
  const std::vector<int> plane = {setup.height, setup.width};
  wire_.t = t;
  wire_.cameras.clear();
  wire_.images.clear();
  for (size_t c = 0; c < renderer_->cameras(); ++c) {
    const ObsImages& im = renderer_->images(c);
    const std::string& name = setup.cameras[c].name;
    const ObsCameraGeometry& g = im.geometry;
    wire_.cameras.push_back({name, g.fovy, g.fx, g.fy, g.cx, g.cy, g.pose});
    for (Layer layer : setup.layers) {
      WireImage w;
      w.name = name;
      w.shape = plane;
      if (layer == Layer::kRgb) {
        w.shape.push_back(3);
        w.data = im.rgb.data();
        w.bytes = im.rgb.size();
      } else if (layer == Layer::kDepth) {
        w.layer = "depth";
        w.dtype = "float32";
        w.data = im.depth.data();
        w.bytes = im.depth.size() * sizeof(float);
      } else {
        w.layer = "segmentation";
        w.dtype = "int32";
        w.data = im.segmentation.data();
        w.bytes = im.segmentation.size() * sizeof(int32_t);
      }
      wire_.images.push_back(std::move(w));
    }
  }
}

void PixelRecorder::End() {
  if (!plan_.stages()) return;
  Job job;
  job.kind = Job::kClose;
  Push(std::move(job));
  {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait(lock, [&] { return (queue_.empty() && !busy_) || error_; });
  }
  RethrowError();
}

void PixelRecorder::Write(const Job& job) {
  if (job.kind == Job::kOpen) {
    writer_.reset();
    writer_ = std::make_unique<PixelStagingWriter>(StagingFileOf(plan_.staging, job.index),
                                                   plan_.layout.deflate_level);
    return;
  }
  if (!writer_) throw RunError("PixelRecorder: an episode's images before its Begin");
  if (job.kind == Job::kClose) {
    writer_->Close();
    writer_.reset();
    return;
  }
  const int t = job.t;
  if (plan_.layout.states) writer_->AddState(t, job.state);
  const PixelLayout& layout = plan_.layout;
  for (size_t c = 0; c < job.images.size(); ++c) {
    const ObsImages& im = job.images[c];
    const int camera = static_cast<int>(c);
    if (layout.has(ImageLayer::kRgb)) {
      if (layout.raw_rgb)
        writer_->AddImage(camera, ImageLayer::kRgb, t, im.rgb.data(), im.rgb.size());
      if (layout.png_rgb) {
        writer_->AddPng(camera, t,
                        EncodePng(layout.width, layout.height, 3, 8, im.rgb.data(), true,
                                  "image of camera " + layout.cameras[c].name));
      }
    }
    if (layout.has(ImageLayer::kDepth)) {
      writer_->AddImage(camera, ImageLayer::kDepth, t, im.depth.data(), im.depth.size() * 4);
    }
    if (layout.has(ImageLayer::kSegmentation)) {
      writer_->AddImage(camera, ImageLayer::kSegmentation, t, im.segmentation.data(),
                        im.segmentation.size() * 4);
    }
    const ObsCameraGeometry& g = im.geometry;
    std::array<double, 12> numbers = {g.fovy, g.fx, g.fy, g.cx, g.cy};
    std::copy(g.pose.begin(), g.pose.end(), numbers.begin() + 5);
    writer_->AddGeometry(camera, t, numbers);
  }
}

}  // namespace fetchscope
