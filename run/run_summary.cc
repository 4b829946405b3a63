#include "run/run_summary.h"

#include <cstdio>
#include <sstream>

namespace fetchscope {
namespace {

// "success 2/3 complete, 1 incomplete (not in the rate)"
std::string SuccessText(const EpisodeCounts& c) {
  std::string s =
      "success " + std::to_string(c.successes) + "/" + std::to_string(c.complete) + " complete";
  if (c.incomplete) s += ", " + std::to_string(c.incomplete) + " incomplete (not in the rate)";
  return s;
}

}  // namespace

EpisodeCounts CountEpisodes(const std::vector<ManifestEpisode>& episodes) {
  EpisodeCounts c;
  for (const ManifestEpisode& e : episodes) {
    if (e.complete.value_or(true)) {
      ++c.complete;
      c.successes += e.is_success;
    } else {
      ++c.incomplete;
    }
  }
  return c;
}

std::string ResumeCommand(const std::string& command_line) {
  std::istringstream in(command_line);
  std::string word, out;
  bool resume = false;
  while (in >> word) {
    if (word == "--overwrite") continue;
    resume = resume || word == "--resume";
    out += (out.empty() ? "" : " ") + word;
  }
  return resume ? out : out + " --resume";
}

std::string RecordSummaryText(const RecordSummary& s) {
  char head[320];
  std::snprintf(head, sizeof(head),
                "record: %zu episode(s), %ld frames in %.1f s (%.1f frames/s, %.2f episodes/s, %d "
                "job(s)%s%s)",
                s.recorded, s.frames, s.wall_s, s.frames / s.wall_s, s.recorded / s.wall_s, s.jobs,
                s.shard.empty() ? "" : ", shard ", s.shard.c_str());
  std::string text = head;
  if (s.kept) text += ", " + std::to_string(s.kept) + " kept by --resume";
  text += ", " + SuccessText(CountEpisodes(s.episodes));
  if (s.missing) text += ", " + std::to_string(s.missing) + " missing";
  text += ", " + s.renderer + " via " + s.backend + ", " + s.codec + " -> " + s.out;
  if (s.interrupted) {
    text += " (interrupted)\nrecord: to record the rest, run: " + ResumeCommand(s.command_line);
  }
  return text;
}

std::string AlreadyCompleteText(const std::string& out, const std::vector<ManifestEpisode>& kept) {
  return "record: --out '" + out + "' already holds the whole run (" + std::to_string(kept.size()) +
         " episode(s)): nothing to record; " + SuccessText(CountEpisodes(kept));
}

}  // namespace fetchscope
