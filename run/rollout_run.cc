#include "run/rollout_run.h"

#include <signal.h>

#include <memory>
#include <optional>

#include "base/errors.h"
#include "dataset/minari_writer.h"
#include "render/view.h"
#include "run/episode_look.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy.h"
#include "src/trajectory.h"

namespace fetchscope {
namespace {

// Plays episodes and reports each as its trajectory JSON entry.
class RolloutRunner : public EpisodeRunner {
 public:
  RolloutRunner(const RolloutJob& job, int worker)
      : job_(job),
        worker_(worker),
        sequence_(std::make_unique<FetchEnv>(*job.spec, job.assets),
                  MakePolicy(job.policy, *job.spec, WithImages(*job.policy_context, &pixels_)),
                  job.policy_context->seed, job.steps) {
    if (job.contact_signals) sequence_.env().EnableContactSignals();
    sequence_.SetStopAfterSuccess(job.stop_after_success);
  }
  ~RolloutRunner() override {
    pixels_.reset();  // its renderers go while their GL context exists
    gl_.reset();
  }
  nlohmann::json Start() override {
    if (job_.pixels.enabled()) {
      if (job_.pixels.setup.enabled()) gl_ = CreateViewContext(job_.backend, job_.gpu, worker_);
      pixels_.emplace(job_.pixels, gl_.get(), sequence_.env().model());
    }
    return nullptr;
  }
  void Run(int k, WorkerChannel& channel) override {
    std::optional<LookDraw> look;
    if (pixels_) {
      look = EpisodeLook(job_.look, job_.look_seed.value_or(job_.seed), k, nullptr,
                         pixels_->camera_keys(), sequence_.env().model());
      pixels_->SetLook(look ? &*look : nullptr);
    }
    if (pixels_) pixels_->Begin(k);
    EpisodeRecord episode = sequence_.Play(k, [&](const StepRecord& record, const StepResult*) {
      if (pixels_) pixels_->Step(sequence_.env(), record);
      return !channel.StopRequested();
    });
    if (pixels_) pixels_->End();
    if (look) episode.look = LookJson(*look);
    channel.Progress(static_cast<int>(episode.steps.size()) - 1);
    channel.Done(k, EpisodeJson(episode));
  }

 private:
  const RolloutJob& job_;
  const int worker_;
  EpisodeSequence sequence_;
  std::unique_ptr<GlContext> gl_;
  std::optional<PixelRecorder> pixels_;
};

// One episode's JSON entry as the trajectory reader reads it back: what the output receives.
EpisodeRecord ReadBack(const RolloutJob& job, const nlohmann::json& episode) {
  Trajectory one =
      ParseTrajectoryJson(TrajectoryJson(*job.spec, job.assets, job.seed, job.policy.text,
                                         nlohmann::json::array({episode})),
                          "rollout");
  return std::move(one.episodes.front());
}

}  // namespace

OutputRun RolloutOutputRun(const RolloutJob& job) {
  OutputRun run;
  run.command = "rollout";
  run.spec = job.spec;
  run.seed = job.seed;
  run.seed_text = job.seed_text;
  run.policy = job.policy.text;
  run.episodes =
      job.episodes_requested > 0 ? job.episodes_requested : static_cast<int>(job.episodes.size());
  run.steps = job.steps;
  return run;
}

RolloutResult RunRolloutJob(const RolloutJob& job) {
  EpisodeOutput* output = job.output;
  if (output) output->Begin(RolloutOutputRun(job));  // an existing id fails now, not after
  std::optional<EpisodesInOrder> in_order;
  ScheduleOptions schedule;
  schedule.episodes = job.episodes;
  if (output) in_order.emplace(job.episodes, *output);
  if (output || job.on_episode) {
    schedule.on_done = [&](int, const nlohmann::json& e) {
      if (output && !in_order->stopped()) in_order->Done(ReadBack(job, e));
      if (job.on_episode) job.on_episode();
    };
  }
  schedule.jobs = job.jobs;
  schedule.mode = job.mode;
  if (!job.keep_trajectories) {
    schedule.keep = [](const nlohmann::json& e) {
      return nlohmann::json{{"is_success", e.at("is_success")}};
    };
  }
  const ScheduleResult result = RunEpisodes(
      schedule, [&](int worker) { return std::make_unique<RolloutRunner>(job, worker); });
  RolloutResult r;
  if (!result.failures.empty()) {
    if (output) output->Abort();
    if (result.failures.front().usage) throw UsageError(result.failures.front().message);
    throw RunError(DescribeFailures(result));
  }
  if (result.signal) {
    if (output) output->Abort();
    r.signal = result.signal;
    r.stopped = std::string("interrupted (") + (r.signal == SIGINT ? "SIGINT" : "SIGTERM") + ")";
    return r;
  }
  try {
    if (output) r.output = output->Finish();
  } catch (const MinariInterrupted& e) {  // a signal after the last episode: still nothing
    output->Abort();
    r.signal = e.signal;
    r.stopped = e.what();
    return r;
  }
  for (const auto& [k, episode] : result.results) {
    r.successes += episode.at("is_success").get<bool>();
    if (job.keep_trajectories) r.episodes.push_back(episode);
  }
  return r;
}

}  // namespace fetchscope
