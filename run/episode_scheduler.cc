#include "run/episode_scheduler.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "base/cores.h"
#include "base/errors.h"
#include "base/process.h"
#include "base/stop_signal.h"

namespace fetchscope {
namespace {

// ---- the wire between a worker process and the parent: one JSON object per line ----
//
// worker -> parent: {"t":"ready","info":...}  {"t":"next"}  {"t":"progress","n":N}
//                   {"t":"done","episode":K,"result":...}  {"t":"error","message":...,"usage":B}
// parent -> worker: {"t":"episode","k":K}  {"t":"quit"}

// How often the parent beats on_progress(0) while no message comes: the progress line stays
// alive while an episode makes no frames. A timer only: stops end the wait at once.
constexpr int kBeatMs = 100;

std::string EpisodeList(const std::vector<int>& episodes) {
  std::string out;
  for (int k : episodes) out += (out.empty() ? "" : ", ") + std::to_string(k);
  return out;
}

// The channel of a worker process: everything goes to the parent over its socket. Progress is
// batched (a message per kProgressBatch frames, or when an episode is reported). Done may come
// from a runner's encoder threads, hence the lock.
class SocketChannel : public WorkerChannel {
 public:
  explicit SocketChannel(LineChannel& parent) : parent_(parent) {}
  void Progress(int n) override {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ += n;
    if (pending_ >= kProgressBatch) FlushLocked();
  }
  void Done(int episode, nlohmann::json result) override {
    std::lock_guard<std::mutex> lock(mutex_);
    FlushLocked();
    parent_.Send({{"t", "done"}, {"episode", episode}, {"result", std::move(result)}});
  }
  bool StopRequested() const override { return StopSignal() != 0; }
  void Send(const nlohmann::json& message) {
    std::lock_guard<std::mutex> lock(mutex_);
    FlushLocked();
    parent_.Send(message);
  }

 private:
  static constexpr int kProgressBatch = 10;
  void FlushLocked() {
    if (pending_ == 0) return;
    parent_.Send({{"t", "progress"}, {"n", pending_}});
    pending_ = 0;
  }
  LineChannel& parent_;
  std::mutex mutex_;
  int pending_ = 0;
};

// The body of a worker process. Returns its exit status.
int WorkerMain(int worker, LineChannel& parent, const RunnerFactory& factory) {
  SocketChannel channel(parent);
  try {
    std::unique_ptr<EpisodeRunner> runner = factory(worker);
    channel.Send({{"t", "ready"}, {"info", runner->Start()}});
    while (true) {
      channel.Send({{"t", "next"}});
      // only this thread reads the socket; runners' threads only write to it
      const std::optional<nlohmann::json> message = parent.Receive();
      if (!message || message->at("t") != "episode") break;
      runner->Run(message->at("k").get<int>(), channel);
    }
    runner->Finish(channel);
    runner.reset();  // GL context, encoders and policy children go now, in this process
    return 0;
  } catch (const UsageError& e) {
    channel.Send({{"t", "error"}, {"message", e.what()}, {"usage", true}});
    return 2;
  } catch (const std::exception& e) {
    channel.Send({{"t", "error"}, {"message", e.what()}, {"usage", false}});
    return 1;
  }
}

// The parent's view of one worker process.
struct WorkerProcess {
  int worker = 0;
  ChildProcess child;  // killed and reaped if the scheduler leaves early (an exception)
  bool alive = true;
  bool reported_error = false;
  std::vector<int> in_hand;  // episodes given and not yet reported
};

class ProcessScheduler {
 public:
  ProcessScheduler(const ScheduleOptions& options, const RunnerFactory& factory, int jobs)
      : options_(options), factory_(factory), jobs_(jobs) {}

  ScheduleResult Run() {
    result_.jobs = jobs_;
    result_.workers.assign(jobs_, nullptr);
    Spawn();
    while (
        std::any_of(procs_.begin(), procs_.end(), [](const WorkerProcess& p) { return p.alive; })) {
      ForwardStopSignal();
      std::vector<pollfd> fds;
      std::vector<WorkerProcess*> owners;
      for (WorkerProcess& p : procs_) {
        if (!p.alive) continue;
        fds.push_back({p.child.channel().in_fd(), POLLIN, 0});
        owners.push_back(&p);
      }
      // a stop ends the wait at once, until it has been forwarded
      const WaitEnd end = WaitForInput(&fds, kBeatMs, /*watch_stop=*/forwarded_ == 0);
      if (end == WaitEnd::kStop) ForwardStopSignal();
      // a heartbeat: the progress line stays alive while an episode makes no frames
      if (options_.on_progress) options_.on_progress(0);
      for (size_t i = 0; i < fds.size(); ++i) {
        if (fds[i].revents == 0) continue;
        WorkerProcess& p = *owners[i];
        const bool open = p.child.channel().ReadSome();
        while (std::optional<nlohmann::json> message = p.child.channel().TakeMessage()) {
          Handle(p, *message);
        }
        if (!open) Reap(p);
      }
    }
    return std::move(result_);
  }

 private:
  void Spawn() {
    procs_.reserve(jobs_);
    for (int w = 0; w < jobs_; ++w) {
      // The worker: its own process group, so a terminal's Ctrl-C reaches only the parent,
      // which forwards it; and it dies with the parent, so none is ever orphaned (Fork).
      ChildProcess child = ChildProcess::Fork([this, w](LineChannel& parent) {
        InstallStopSignals();
        for (WorkerProcess& other : procs_) other.child.channel().Close();
        return WorkerMain(w, parent, factory_);
      });
      result_.pids.push_back(child.pid());
      WorkerProcess p;
      p.worker = w;
      p.child = std::move(child);
      procs_.push_back(std::move(p));
    }
  }

  // The first SIGINT/SIGTERM is passed to every worker, which ends its episode early.
  void ForwardStopSignal() {
    const int sig = StopSignal();
    if (sig != 0) Stop(sig);
  }

  // Stops the run as interrupted by `sig` (SIGINT or SIGTERM), once.
  void Stop(int sig) {
    if (forwarded_ != 0) return;
    forwarded_ = sig;
    result_.signal = sig;
    stop_assigning_ = true;
    for (const WorkerProcess& p : procs_) {
      if (p.alive) p.child.Signal(sig);
    }
  }

  void Handle(WorkerProcess& p, const nlohmann::json& message) {
    const std::string type = message.at("t");
    if (type == "ready") {
      result_.workers[p.worker] = message.at("info");
    } else if (type == "next") {
      ForwardStopSignal();
      if (!stop_assigning_ && next_ < options_.episodes.size()) {
        const int k = options_.episodes[next_++];
        p.in_hand.push_back(k);
        p.child.channel().Send({{"t", "episode"}, {"k", k}});
      } else {
        p.child.channel().Send({{"t", "quit"}});
      }
    } else if (type == "progress") {
      if (options_.on_progress) options_.on_progress(message.at("n").get<int>());
    } else if (type == "done") {
      const int k = message.at("episode");
      p.in_hand.erase(std::remove(p.in_hand.begin(), p.in_hand.end(), k), p.in_hand.end());
      const nlohmann::json& result = message.at("result");
      if (options_.on_done) options_.on_done(k, result);
      result_.results[k] = options_.keep ? options_.keep(result) : result;
    } else if (type == "error") {
      p.reported_error = true;
      Fail(p, message.at("message").get<std::string>(), message.value("usage", false));
    }
  }

  void Fail(WorkerProcess& p, const std::string& message, bool usage) {
    WorkerFailure failure;
    failure.worker = p.worker;
    failure.episodes = p.in_hand;
    failure.message = message;
    failure.usage = usage;
    result_.failures.push_back(std::move(failure));
    p.in_hand.clear();
    stop_assigning_ = true;
  }

  void Reap(WorkerProcess& p) {
    const pid_t pid = p.child.pid();
    p.child.channel().Close();
    p.alive = false;
    const ChildExit status = p.child.Wait();
    if (p.reported_error) return;
    if (status.ok() && p.in_hand.empty()) return;
    if (status.interrupted()) {
      // stopped from outside (a hangup, a stop signal before its handler was in place): the
      // run is interrupted, not failed, and what it had in hand is missing. result.signal
      // stays SIGINT or SIGTERM, which the commands name: a hangup stops as SIGTERM does.
      p.in_hand.clear();
      Stop(status.signal == SIGINT ? SIGINT : SIGTERM);
      return;
    }
    Fail(p,
         "worker " + std::to_string(p.worker) + " (pid " + std::to_string(pid) + ") " +
             status.Describe(),
         false);
  }

  const ScheduleOptions& options_;
  const RunnerFactory& factory_;
  int jobs_;
  std::vector<WorkerProcess> procs_;
  size_t next_ = 0;
  bool stop_assigning_ = false;
  int forwarded_ = 0;
  ScheduleResult result_;
};

// MuJoCo 2.2 binds its GL functions at the first mjr_makeContext of a process: runners of one
// process start one at a time so that no two threads race through that.
std::mutex g_start_mutex;

class ThreadScheduler {
 public:
  ThreadScheduler(const ScheduleOptions& options, const RunnerFactory& factory, int jobs)
      : options_(options), factory_(factory), jobs_(jobs), in_hand_(jobs) {}

  ScheduleResult Run() {
    result_.jobs = jobs_;
    result_.workers.assign(jobs_, nullptr);
    result_.pids.assign(jobs_, getpid());
    std::vector<std::thread> threads;
    for (int w = 1; w < jobs_; ++w) threads.emplace_back([this, w] { Work(w); });
    // a heartbeat once a second: the progress line stays alive while an episode makes no
    // frames (a slow exec: policy)
    bool finished = false;
    std::condition_variable beat;
    std::thread heartbeat([&] {
      std::unique_lock<std::mutex> lock(mutex_);
      while (!beat.wait_for(lock, std::chrono::seconds(1), [&] { return finished; })) {
        if (options_.on_progress) options_.on_progress(0);
      }
    });
    Work(0);  // worker 0 on this thread
    for (std::thread& t : threads) t.join();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      finished = true;
    }
    beat.notify_all();
    heartbeat.join();
    result_.signal = StopSignal();
    return std::move(result_);
  }

 private:
  class Channel : public WorkerChannel {
   public:
    Channel(ThreadScheduler* scheduler, int worker) : s_(*scheduler), worker_(worker) {}
    void Progress(int n) override {
      std::lock_guard<std::mutex> lock(s_.mutex_);
      if (s_.options_.on_progress) s_.options_.on_progress(n);
    }
    void Done(int episode, nlohmann::json result) override {
      std::lock_guard<std::mutex> lock(s_.mutex_);
      std::vector<int>& hand = s_.in_hand_[worker_];
      hand.erase(std::remove(hand.begin(), hand.end(), episode), hand.end());
      if (s_.options_.on_done) s_.options_.on_done(episode, result);
      s_.result_.results[episode] = s_.options_.keep ? s_.options_.keep(result) : std::move(result);
    }
    bool StopRequested() const override { return StopSignal() != 0; }

   private:
    ThreadScheduler& s_;
    int worker_;
  };

  // Claims the next episode for worker w, or -1 when there is none to start.
  int Claim(int w) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stop_assigning_ || StopSignal() != 0 || next_ >= options_.episodes.size()) return -1;
    const int k = options_.episodes[next_++];
    in_hand_[w].push_back(k);
    return k;
  }

  void Work(int w) {
    Channel channel(this, w);
    try {
      std::unique_ptr<EpisodeRunner> runner;
      {
        std::lock_guard<std::mutex> start(g_start_mutex);
        runner = factory_(w);
        nlohmann::json info = runner->Start();
        std::lock_guard<std::mutex> lock(mutex_);
        result_.workers[w] = std::move(info);
      }
      for (int k; (k = Claim(w)) >= 0;) runner->Run(k, channel);
      runner->Finish(channel);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex_);
      WorkerFailure failure;
      failure.worker = w;
      failure.episodes = in_hand_[w];
      failure.message = e.what();
      failure.usage = dynamic_cast<const UsageError*>(&e) != nullptr;
      result_.failures.push_back(std::move(failure));
      in_hand_[w].clear();
      stop_assigning_ = true;
    }
  }

  const ScheduleOptions& options_;
  const RunnerFactory& factory_;
  int jobs_;
  std::mutex mutex_;  // guards everything below
  size_t next_ = 0;
  bool stop_assigning_ = false;
  std::vector<std::vector<int>> in_hand_;
  ScheduleResult result_;
};

}  // namespace

ScheduleResult RunEpisodes(const ScheduleOptions& options, const RunnerFactory& factory) {
  InstallStopSignals();
  const int jobs = std::max(1, std::min<int>(options.jobs, options.episodes.size()));
  ScheduleResult result = jobs > 1 && options.mode == WorkerMode::kProcess
                              ? ProcessScheduler(options, factory, jobs).Run()
                              : ThreadScheduler(options, factory, jobs).Run();
  for (int k : options.episodes) {
    if (!result.results.count(k)) result.missing.push_back(k);
  }
  return result;
}

int ResolveJobs(int jobs, int episodes) {
  const int cores = UsableCores().usable;
  return std::max(1, std::min(jobs == 0 ? cores : jobs, std::max(1, episodes)));
}

std::string DescribeFailures(const ScheduleResult& result) {
  std::string out;
  for (const WorkerFailure& f : result.failures) {
    if (!out.empty()) out += "; ";
    out += f.message;
    if (!f.episodes.empty()) {
      out += std::string(" (lost episode") + (f.episodes.size() > 1 ? "s " : " ") +
             EpisodeList(f.episodes) + ")";
    }
  }
  return out;
}

}  // namespace fetchscope
