// fetchscope datasets: the Minari datasets under the datasets root, as `minari list local`
// lists them, with what a Fetch user wants to know first (env, steps, seeds, who wrote it).
#include <cstdio>
#include <filesystem>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/text_table.h"
#include "cli/command.h"
#include "dataset/minari_format.h"
#include "dataset/minari_reader.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;

struct DatasetsOptions {
  std::string minari_root;
  bool json = false;
};

// MB of the files under data/ (Minari's get_size), one decimal
std::string SizeMb(const fs::path& data) {
  std::error_code ec;
  uintmax_t bytes = 0;
  for (const auto& entry : fs::directory_iterator(data, ec)) {
    if (entry.is_regular_file(ec)) bytes += entry.file_size(ec);
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", static_cast<double>(bytes) / 1e6);
  return buf;
}

int RunDatasets(const DatasetsOptions& o) {
  const fs::path root = MinariRoot(o.minari_root);
  std::error_code ec;
  const bool exists = fs::exists(root, ec);
  if (exists) {
    fs::directory_iterator(root, ec);
    if (ec)
      throw RunError("cannot list the datasets root '" + root.string() + "': " + ec.message());
  }
  const std::vector<std::string> ids = ListLocalMinariIds(root);
  nlohmann::json out = nlohmann::json::array();
  std::vector<std::vector<std::string>> rows = {
      {"id", "env", "episodes", "steps", "size MB", "seeds", "written by"}};
  for (const std::string& id : ids) {
    nlohmann::json j = {{"id", id}};
    try {
      const MinariDataset d = ReadMinariDataset(id, root);
      const MinariMetadata& m = d.metadata;
      size_t seeded = 0;
      for (const MinariEpisode& e : d.episodes) seeded += e.seed.has_value();
      const std::string seeds =
          seeded == d.episodes.size() ? "all"
          : seeded == 0               ? "none"
                        : std::to_string(seeded) + " of " + std::to_string(d.episodes.size());
      const bool ours = m.code_permalink.rfind("fetchscope ", 0) == 0;
      const std::string size = SizeMb(d.location.hdf5.parent_path());
      j["env"] = m.env_id ? nlohmann::json(*m.env_id) : nullptr;
      j["episodes"] = m.total_episodes;
      j["steps"] = m.total_steps;
      j["size_mb"] = std::stod(size);
      j["seeded_episodes"] = seeded;
      j["fetchscope"] = ours;
      rows.push_back({id, m.env_id.value_or("(no env_spec)"), std::to_string(m.total_episodes),
                      std::to_string(m.total_steps), size, seeds, ours ? "fetchscope" : "other"});
    } catch (const std::exception& e) {  // one bad dataset does not hide the others
      j["error"] = e.what();
      rows.push_back({id, std::string("unreadable: ") + e.what()});
    }
    out.push_back(j);
  }
  if (o.json) {
    std::printf("%s\n",
                DumpJson(nlohmann::json{{"root", root.string()}, {"datasets", out}}).c_str());
    return 0;
  }
  if (ids.empty()) {
    std::printf("no Minari datasets under %s%s\n", root.c_str(),
                exists ? "" : " (the folder does not exist yet)");
    return 0;
  }
  std::printf("Minari datasets under %s:\n%s", root.c_str(), AlignColumns(rows).c_str());
  return 0;
}

}  // namespace

Command AddDatasets(CLI::App& app) {
  auto o = std::make_shared<DatasetsOptions>();
  CLI::App* sub = app.add_subcommand(
      "datasets",
      "List the local Minari datasets: id, env, episodes, steps, size, seeds, who wrote them");
  sub->add_option("--minari-root", o->minari_root,
                  "Datasets root (default $MINARI_DATASETS_PATH, else ~/.minari/datasets)");
  sub->add_flag("--json", o->json, "Print JSON instead of a table");
  return {sub, [o] { return RunDatasets(*o); }};
}

}  // namespace fetchscope::cli
