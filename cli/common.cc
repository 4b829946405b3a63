#include "cli/common.h"

#include <mujoco/mujoco.h>
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <utility>

#include "base/atomic_file.h"
#include "base/errors.h"
#include "base/json_util.h"
#include "base/suggest.h"

namespace fetchscope::cli {

void AddEnvOptions(CLI::App* sub, EnvOptions* options, bool with_seed) {
  options->env_id_option =
      sub->add_option(
             "--env-id", options->env_id,
             "FetchReach-v4, FetchReachDense-v4, FetchPush[Dense]-v4, "
             "FetchPickAndPlace[Dense]-v4, FetchSlide[Dense]-v4, or auto (FetchReachDense-v4)")
          ->capture_default_str();
  sub->add_option("--assets", options->assets,
                  "bundled (our models/), auto ($FETCHSCOPE_ASSETS, else an installed "
                  "gymnasium_robotics, else bundled), or a Gymnasium-Robotics envs/assets folder")
      ->capture_default_str();
  if (with_seed) {
    options->seed_option =
        sub->add_option("--seed", options->seed,
                        "env.reset(seed=S) for the first episode (later episodes continue the "
                        "generator) and action_space.seed(S) for the random policy")
            ->capture_default_str();
  }
}

uint64_t ParseSeed(const std::string& text) {
  const std::string accepted =
      ": a seed is a non-negative integer below 2^64, as Gymnasium accepts";
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) {
    throw UsageError("--seed '" + text + "' is not valid" + accepted);
  }
  errno = 0;
  char* end = nullptr;
  unsigned long long v = std::strtoull(text.c_str(), &end, 10);
  if (errno == ERANGE || *end != '\0')
    throw UsageError("--seed '" + text + "' is too large" + accepted);
  return v;
}

std::string JsonOutPath(const std::string& prefix, const std::string& suffix) {
  if (prefix.empty()) return "";
  if (prefix.size() >= 5 && prefix.compare(prefix.size() - 5, 5, ".json") == 0) return prefix;
  if (prefix.back() == '/') return prefix + suffix + ".json";
  return prefix + "_" + suffix + ".json";
}

namespace {

// "FetchReach-v4 seed 0", "task Push seed 3": an identity as a message tells it.
std::string DescribeIdentity(const ResultIdentity& identity, const nlohmann::json& source) {
  std::string text;
  for (const auto& [key, ignored] : identity) {
    if (!source.contains(key)) continue;
    const nlohmann::json& v = source.at(key);
    const std::string value = v.is_string() ? v.get<std::string>() : v.dump();
    text += (text.empty() ? "" : " ") + (key == "env_id" ? value : key + " " + value);
  }
  return text.empty() ? "unnamed" : text;
}

}  // namespace

void CheckJsonOutReplaces(const std::string& path, const ResultIdentity& identity, bool overwrite) {
  if (overwrite || path.empty()) return;
  std::ifstream in(path, std::ios::binary);
  if (!in) return;
  const nlohmann::json old = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!old.is_object() || !old.contains("assets")) return;  // not a result fetchscope wrote
  nlohmann::json now = nlohmann::json::object();
  bool same = true;
  for (const auto& [key, value] : identity) {
    now[key] = value;
    if (old.contains(key) && old.at(key) != value) same = false;
  }
  if (same) return;
  throw UsageError(path + " holds " + DescribeIdentity(identity, old) + " results; this run is " +
                   DescribeIdentity(identity, now) +
                   ": pass --overwrite to replace them, or another --json-out");
}

std::string& CommandLine() {
  static std::string line;
  return line;
}

void AddDatasetAuthorOptions(CLI::App* sub, DatasetAuthor* author) {
  sub->add_option("--minari-author", author->name,
                  "The dataset's metadata `author` (default fetchscope)");
  sub->add_option("--minari-author-email", author->email,
                  "The dataset's metadata `author_email` (default: none)");
}

void AddSignalsOption(CLI::App* sub, std::string* signals) {
  sub->add_option("--signals", *signals,
                  "Per-step signals added to each step of the trajectory JSON: none, or contacts "
                  "(the left and right finger's normal force on the object in N, whether the "
                  "object touches the table, and every active contact with its geoms, position, "
                  "normal force and penetration; the state after the step, as MuJoCo's d->contact "
                  "holds it). Recording them never changes the simulation")
      ->capture_default_str();
}

bool ParseContactSignals(const std::string& signals) {
  if (signals == "none") return false;
  if (signals == "contacts") return true;
  throw UsageError("--signals '" + signals + "' is not known" +
                   DidYouMean(signals, {"none", "contacts"}) + "; accepted: none, contacts");
}

}  // namespace fetchscope::cli
