#include "run/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>

#include "base/errors.h"
#include "base/number_format.h"

namespace fetchscope {
namespace {

double SteadySeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// FETCHSCOPE_PROGRESS_INTERVAL: seconds between log lines when stderr is not a terminal.
double LogIntervalFromEnvironment() {
  const char* text = std::getenv("FETCHSCOPE_PROGRESS_INTERVAL");
  if (!text || !*text) return 30;
  char* end = nullptr;
  const double seconds = std::strtod(text, &end);
  if (*end != '\0' || !(seconds >= 0.1 && seconds <= 86400)) {
    throw UsageError(std::string("FETCHSCOPE_PROGRESS_INTERVAL '") + text +
                     "' is not accepted: seconds between progress lines, 0.1 to 86400");
  }
  return seconds;
}

}  // namespace

ProgressReporter::ProgressReporter(const std::string& label, int episodes, long frames_per_episode,
                                   bool quiet)
    : ProgressReporter(
          [&] {
            Options o;
            o.label = label;
            o.episodes = episodes;
            o.frames_per_episode = frames_per_episode;
            o.quiet = quiet;
            o.terminal = isatty(STDERR_FILENO);
            o.log_interval_s = LogIntervalFromEnvironment();
            return o;
          }(),
          SteadySeconds) {}

ProgressReporter ProgressReporter::ForLongRuns(const std::string& label, int episodes,
                                               long units_per_episode, const std::string& unit) {
  Options o;
  o.label = label;
  o.episodes = episodes;
  o.frames_per_episode = units_per_episode;
  o.terminal = isatty(STDERR_FILENO);
  o.log_interval_s = LogIntervalFromEnvironment();
  o.log_percent_step = 0;
  o.unit = unit;
  return ProgressReporter(o, SteadySeconds);
}

ProgressReporter::ProgressReporter(const Options& options, std::function<double()> clock_s)
    : o_(options), clock_(std::move(clock_s)) {
  start_ = clock_();
  last_log_ = start_;
}

void ProgressReporter::Frames(int n) {
  frames_ += n;
  Update();
}

void ProgressReporter::EpisodeDone(long frames) {
  frames_ += frames;
  ++done_;
  Update();
}

void ProgressReporter::EpisodeDone() {
  ++done_;
  Update();
}

std::string ProgressReporter::Line() const {
  const double elapsed = clock_() - start_;
  const double fps = elapsed > 0 ? frames_ / elapsed : 0;
  const long total = static_cast<long>(o_.episodes) * o_.frames_per_episode;
  const long left = std::max(0L, total - frames_);
  const bool finishing = left == 0 && done_ < o_.episodes;  // every frame made, episodes not
  char eta[32];
  if (finishing) {
    std::snprintf(eta, sizeof(eta), "finishing");
  } else if (fps > 0) {
    // "0 s" only when nothing is left; under a second left reads "1 s"
    std::snprintf(eta, sizeof(eta), "%.0f s", left > 0 ? std::max(1.0, left / fps) : 0.0);
  } else {
    std::snprintf(eta, sizeof(eta), "unknown");
  }
  // frames beyond the finished episodes' are of episodes still running
  const long finished = static_cast<long>(done_) * o_.frames_per_episode;
  char running[64] = "";
  if (frames_ > finished && done_ < o_.episodes) {
    std::snprintf(running, sizeof(running), " (%ld of episodes still running)", frames_ - finished);
  }
  const char* unit = o_.unit.c_str();
  char line[320];
  if (o_.terminal) {  // the bar as it has always been
    std::snprintf(line, sizeof(line), "%s: %d/%d episodes  %s %ld/%ld  %.1f %s/s  ETA %s",
                  o_.label.c_str(), done_, o_.episodes, o_.unit == "frames" ? "frame" : unit,
                  frames_, total, fps, unit, eta);
    return line;
  }
  std::snprintf(line, sizeof(line),
                "%s: progress %d/%d episodes (%s), %ld/%ld %s%s, %.1f %s/s, ETA %s",
                o_.label.c_str(), done_, o_.episodes, PercentText(done_, o_.episodes).c_str(),
                frames_, total, unit, running, fps, unit, eta);
  return line;
}

void ProgressReporter::Update() {
  if (o_.quiet) return;
  const double now = clock_();
  if (o_.terminal) {
    if (last_draw_ >= 0 && now - last_draw_ < 0.1) return;
    last_draw_ = now;
    std::fprintf(o_.out, "\r%s   ", Line().c_str());
    std::fflush(o_.out);
    return;
  }
  const int step = std::max(1, o_.log_percent_step);
  const int percent = o_.episodes > 0 ? 100 * done_ / o_.episodes : 0;
  const int reached = percent / step * step;
  const bool new_step = o_.log_percent_step > 0 && reached > logged_percent_;
  const bool interval = now - last_log_ >= o_.log_interval_s;
  if (!new_step && !interval) return;
  if (new_step) logged_percent_ = reached;
  last_log_ = now;
  std::fprintf(o_.out, "%s\n", Line().c_str());
  std::fflush(o_.out);
}

void ProgressReporter::Clear() {
  if (o_.quiet || !o_.terminal || last_draw_ < 0) return;
  std::fprintf(o_.out, "\r%*s\r", 78, "");
  std::fflush(o_.out);
}

void ProgressReporter::Done(const std::string& summary) {
  if (o_.quiet) return;
  if (o_.terminal) std::fprintf(o_.out, "\r%*s\r", 78, "");
  std::fprintf(o_.out, "%s\n", summary.c_str());
  std::fflush(o_.out);
}

}  // namespace fetchscope
