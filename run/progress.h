// Progress of a batch of episodes on stderr, fed by the episode scheduler in the parent.
//
// On a terminal: one line redrawn in place (at most 10 times a second) with done/total
// episodes, frames, frames/s and ETA, cleared before the summary.
// Not on a terminal (Slurm and Kubernetes logs, a pipe, a file): a plain line
//   "<label>: progress 3/10 episodes (30%), 153/510 frames, 41.7 frames/s, ETA 8 s"
// each time another 10% of the episodes is done and whenever 30 s have passed since the last
// line (FETCHSCOPE_PROGRESS_INTERVAL seconds instead of 30 when set), so a long run shows it is
// alive, even while an episode makes no frames (the scheduler beats once a second), and a short
// one prints no more than ten lines.
#pragma once

#include <chrono>
#include <cstdio>
#include <functional>
#include <string>

namespace fetchscope {

class ProgressReporter {
 public:
  struct Options {
    std::string label = "record";  ///< the line's prefix: the subcommand
    int episodes = 0;              ///< episodes in the run
    long frames_per_episode = 0;   ///< frames (or steps) each episode reports
    bool quiet = false;            ///< print nothing, not even the summary
    bool terminal = false;         ///< redraw one line (true) or print log lines (false)
    double log_interval_s = 30;    ///< log mode: a line at least this often
    int log_percent_step = 10;     ///< log mode: a line each time this % more episodes are done
                                   ///< (0: none, only the interval's lines)
    std::string unit = "frames";   ///< what Frames counts: "frames", or "steps" (rollout)
    std::FILE* out = stderr;
  };

  /// terminal = isatty(stderr); log_interval_s from FETCHSCOPE_PROGRESS_INTERVAL (UsageError
  /// when malformed); the clock is std::chrono::steady_clock.
  ProgressReporter(const std::string& label, int episodes, long frames_per_episode, bool quiet);
  /// As above, for the commands whose output is on stdout (rollout, random-episodes, export):
  /// `unit` counted, and in a log only a line per FETCHSCOPE_PROGRESS_INTERVAL (30 s), so short
  /// runs print nothing.
  static ProgressReporter ForLongRuns(const std::string& label, int episodes,
                                      long units_per_episode, const std::string& unit);
  /// For tests: every option, and a clock in seconds.
  ProgressReporter(const Options& options, std::function<double()> clock_s);

  /// `n` more frames done.
  void Frames(int n);
  /// One more episode done: complete. An episode an interruption ended is not counted (its
  /// frames were).
  void EpisodeDone();
  /// One more episode done with its `frames` (steps) counted at once: for the commands that
  /// count an episode's frames only when it ends (rollout, random-episodes, export).
  void EpisodeDone(long frames);
  /// Clears the terminal line and prints `summary` (unless quiet).
  void Done(const std::string& summary);
  /// Clears the terminal line (a command whose summary goes elsewhere).
  void Clear();

  long frames() const { return frames_; }
  int episodes_done() const { return done_; }

 private:
  void Update();
  std::string Line() const;

  Options o_;
  std::function<double()> clock_;
  double start_ = 0;
  long frames_ = 0;
  int done_ = 0;
  double last_draw_ = -1;   // terminal: last redraw
  double last_log_ = 0;     // log mode: time of the last line
  int logged_percent_ = 0;  // log mode: the last multiple of log_percent_step printed
};

}  // namespace fetchscope
