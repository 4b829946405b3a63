#include "run/episode_scheduler.h"

#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <set>
#include <thread>

#include "base/errors.h"
#include "base/json_util.h"
#include "cli/common.h"

namespace fetchscope::cli {
namespace {

// ---- the wire between a worker process and the parent: one JSON object per line ----
//
// worker -> parent: {"t":"ready","info":...}  {"t":"next"}  {"t":"progress","n":N}
//                   {"t":"done","episode":K,"result":...}  {"t":"error","message":...,"usage":B}
// parent -> worker: {"t":"episode","k":K}  {"t":"quit"}

// Writes all of `line`; false when the peer is gone. MSG_NOSIGNAL: no SIGPIPE.
bool SendLine(int fd, const std::string& line) {
  size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = send(fd, line.data() + done, line.size() - done, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

bool SendMessage(int fd, const nlohmann::json& message) {
  return SendLine(fd, DumpJson(message, -1) + "\n");
}

// Reads what is available into `inbox`; false at end of file or on an error.
bool ReadAvailable(int fd, std::string* inbox) {
  char buffer[65536];
  while (true) {
    const ssize_t n = read(fd, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    inbox->append(buffer, static_cast<size_t>(n));
    return true;
  }
}

// Takes the complete lines off the front of `inbox`.
std::vector<nlohmann::json> TakeMessages(std::string* inbox) {
  std::vector<nlohmann::json> messages;
  size_t start = 0, end;
  while ((end = inbox->find('\n', start)) != std::string::npos) {
    messages.push_back(nlohmann::json::parse(inbox->begin() + start, inbox->begin() + end));
    start = end + 1;
  }
  inbox->erase(0, start);
  return messages;
}

// Blocks for the next whole message (worker side); nullopt when the parent is gone.
std::optional<nlohmann::json> ReceiveMessage(int fd, std::string* inbox) {
  while (true) {
    const size_t end = inbox->find('\n');
    if (end != std::string::npos) {
      nlohmann::json message = nlohmann::json::parse(inbox->begin(), inbox->begin() + end);
      inbox->erase(0, end + 1);
      return message;
    }
    if (!ReadAvailable(fd, inbox)) return std::nullopt;
  }
}

// "signal 9 (SIGKILL: Killed)": the number, the name users grep for, and the description.
std::string SignalName(int sig) {
  const char* abbrev = sigabbrev_np(sig);
  const char* description = sigdescr_np(sig);
  std::string text = "signal " + std::to_string(sig);
  if (abbrev)
    text +=
        std::string(" (SIG") + abbrev + (description ? std::string(": ") + description : "") + ")";
  return text;
}

std::string EpisodeList(const std::vector<int>& episodes) {
  std::string out;
  for (int k : episodes) out += (out.empty() ? "" : ", ") + std::to_string(k);
  return out;
}

// The channel of a worker process: everything goes to the parent over the socket. Progress is
// batched (a message per kProgressBatch frames, or when an episode is reported).
class SocketChannel : public WorkerChannel {
 public:
  explicit SocketChannel(int fd) : fd_(fd) {}
  void Progress(int n) override {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ += n;
    if (pending_ >= kProgressBatch) FlushLocked();
  }
  void Done(int episode, nlohmann::json result) override {
    std::lock_guard<std::mutex> lock(mutex_);
    FlushLocked();
    SendMessage(fd_, {{"t", "done"}, {"episode", episode}, {"result", std::move(result)}});
  }
  bool StopRequested() const override { return StopSignal() != 0; }
  void Send(const nlohmann::json& message) {
    std::lock_guard<std::mutex> lock(mutex_);
    FlushLocked();
    SendMessage(fd_, message);
  }

 private:
  static constexpr int kProgressBatch = 10;
  void FlushLocked() {
    if (pending_ == 0) return;
    SendMessage(fd_, {{"t", "progress"}, {"n", pending_}});
    pending_ = 0;
  }
  int fd_;
  std::mutex mutex_;
  int pending_ = 0;
};

// The body of a worker process. Returns its exit status.
int WorkerMain(int worker, int fd, const RunnerFactory& factory) {
  SocketChannel channel(fd);
  std::string inbox;
  try {
    std::unique_ptr<EpisodeRunner> runner = factory(worker);
    channel.Send({{"t", "ready"}, {"info", runner->Start()}});
    while (true) {
      channel.Send({{"t", "next"}});
      const std::optional<nlohmann::json> message = ReceiveMessage(fd, &inbox);
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
  pid_t pid = -1;
  int fd = -1;
  std::string inbox;
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
        fds.push_back({p.fd, POLLIN, 0});
        owners.push_back(&p);
      }
      const int ready = poll(fds.data(), fds.size(), 100);
      if (ready < 0 && errno != EINTR) throw RunError(std::string("poll: ") + std::strerror(errno));
      // a heartbeat: the progress line stays alive while an episode makes no frames
      if (options_.on_progress) options_.on_progress(0);
      for (size_t i = 0; ready > 0 && i < fds.size(); ++i) {
        if (fds[i].revents == 0) continue;
        WorkerProcess& p = *owners[i];
        const bool open = ReadAvailable(p.fd, &p.inbox);
        for (const nlohmann::json& message : TakeMessages(&p.inbox)) Handle(p, message);
        if (!open) Reap(p);
      }
    }
    return std::move(result_);
  }

 private:
  void Spawn() {
    std::fflush(stdout);
    std::fflush(stderr);
    const pid_t parent = getpid();
    for (int w = 0; w < jobs_; ++w) {
      int sockets[2];
      if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sockets) != 0) {
        throw RunError(std::string("cannot create a worker socket: ") + std::strerror(errno));
      }
      const pid_t pid = fork();
      if (pid < 0)
        throw RunError(std::string("cannot start a worker process: ") + std::strerror(errno));
      if (pid == 0) {
        // The worker: its own process group, so a terminal's Ctrl-C reaches only the parent,
        // which forwards it; and it dies with the parent, so none is ever orphaned.
        setpgid(0, 0);
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent) _exit(1);  // the parent died before prctl
        InstallStopSignals();
        close(sockets[0]);
        for (const WorkerProcess& other : procs_) close(other.fd);
        const int status = WorkerMain(w, sockets[1], factory_);
        std::fflush(stdout);
        std::fflush(stderr);
        _exit(status);
      }
      setpgid(pid, pid);  // also from this side, so a signal sent at once finds the group
      close(sockets[1]);
      WorkerProcess p;
      p.worker = w;
      p.pid = pid;
      p.fd = sockets[0];
      procs_.push_back(std::move(p));
      result_.pids.push_back(pid);
    }
  }

  // The first SIGINT/SIGTERM is passed to every worker, which ends its episode early.
  void ForwardStopSignal() {
    const int sig = StopSignal();
    if (sig == 0 || forwarded_ != 0) return;
    forwarded_ = sig;
    result_.signal = sig;
    stop_assigning_ = true;
    for (const WorkerProcess& p : procs_) {
      if (p.alive) kill(p.pid, sig);
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
        SendMessage(p.fd, {{"t", "episode"}, {"k", k}});
      } else {
        SendMessage(p.fd, {{"t", "quit"}});
      }
    } else if (type == "progress") {
      if (options_.on_progress) options_.on_progress(message.at("n").get<int>());
    } else if (type == "done") {
      const int k = message.at("episode");
      p.in_hand.erase(std::remove(p.in_hand.begin(), p.in_hand.end(), k), p.in_hand.end());
      const nlohmann::json& result = message.at("result");
      if (options_.on_done) options_.on_done(k, result);
      result_.results[k] = result;
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
    close(p.fd);
    p.fd = -1;
    p.alive = false;
    int status = 0;
    while (waitpid(p.pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (p.reported_error) return;
    const bool clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    if (clean && p.in_hand.empty()) return;
    std::string why = WIFSIGNALED(status)
                          ? "died of " + SignalName(WTERMSIG(status))
                          : "exited with status " + std::to_string(WEXITSTATUS(status));
    Fail(p, "worker " + std::to_string(p.worker) + " (pid " + std::to_string(p.pid) + ") " + why,
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
      s_.result_.results[episode] = std::move(result);
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

void AddJobsOptions(CLI::App* sub, int* jobs, std::string* mode) {
  sub->add_option("-j,--jobs", *jobs,
                  "Worker processes, each with its own environment, policy, GL context and "
                  "encoders (0: one per usable core, affinity mask and cgroup quota counted); "
                  "outputs are byte-identical to --jobs 1")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  sub->add_option("--worker-mode", *mode,
                  "process (default) or thread: threads share one process and so one GL driver, "
                  "which serialises them on NVIDIA; kept for comparison (bench --what node)")
      ->capture_default_str()
      ->check(CLI::IsMember({"process", "thread"}));
}

WorkerMode ParseWorkerMode(const std::string& text) {
  if (text == "process") return WorkerMode::kProcess;
  if (text == "thread") return WorkerMode::kThread;
  throw UsageError("--worker-mode '" + text + "' is not known; accepted: process, thread");
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

}  // namespace fetchscope::cli
