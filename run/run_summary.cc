#include "run/run_summary.h"

#include <cstdio>
#include <optional>
#include <vector>

#include "base/process.h"

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
  // the manifest's command line is shell-quoted (cli/main.cc); an older one split at blanks
  const std::optional<std::vector<std::string>> words = SplitShellWords(command_line);
  std::string out;
  bool resume = false;
  for (const std::string& word : words.value_or(std::vector<std::string>{command_line})) {
    if (word == "--overwrite") continue;
    resume = resume || word == "--resume";
    out += (out.empty() ? "" : " ") + (words ? ShellQuote(word) : word);
  }
  return resume ? out : out + " --resume";
}

std::string RecordSummaryText(const Manifest& m, size_t recorded, size_t kept,
                              const std::string& out) {
  const double wall = m.timings_s.wall.value_or(0.0);
  const bool sharded = m.shard && m.shard->count > 1;
  const std::string shard =
      sharded ? ", shard " + std::to_string(m.shard->index) + "/" + std::to_string(m.shard->count)
              : "";
  char head[320];
  std::snprintf(head, sizeof(head),
                "record: %zu episode(s), %ld frames in %.1f s (%.1f frames/s, %.2f episodes/s, %d "
                "job(s)%s)",
                recorded, m.frames, wall, m.frames / wall, recorded / wall, m.jobs, shard.c_str());
  std::string text = head;
  if (kept) text += ", " + std::to_string(kept) + " kept by --resume";
  text += ", " + SuccessText(CountEpisodes(m.episodes));
  if (!m.missing.empty()) text += ", " + std::to_string(m.missing.size()) + " missing";
  auto shown = [](const std::string& s) { return s.empty() ? std::string("?") : s; };
  text += ", " + shown(m.backend.gl_renderer.value_or("")) + " via " +
          shown(m.backend.name.value_or("")) + ", " + m.video.codec.value_or("") + " -> " + out;
  if (m.interrupted) {
    text += " (interrupted)\nrecord: to record the rest, run: " + ResumeCommand(m.command_line);
  }
  return text;
}

std::string AlreadyCompleteText(const std::string& out, const std::vector<ManifestEpisode>& kept) {
  return "record: --out '" + out + "' already holds the whole run (" + std::to_string(kept.size()) +
         " episode(s)): nothing to record; " + SuccessText(CountEpisodes(kept));
}

}  // namespace fetchscope
