#include "dataset/dataset_merge.h"

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "base/confined_file.h"
#include "base/errors.h"
#include "dataset/hdf5_handles.h"
#include "dataset/minari_format.h"
#include "dataset/minari_reader.h"
#include "dataset/minari_writer.h"
#include "dataset/robomimic_writer.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// One shard as read: its file, metadata (Minari) or attributes (robomimic), and selection.
struct ShardFile {
  std::string label;  // as given
  fs::path hdf5;
  json metadata;   // Minari: metadata.json; robomimic: {"env_args", "pixels"} as text
  json selection;  // {"keep", "shard": [I, N], "run", "tried", "kept", "seed", "episodes"}
  H5File file;
};

[[noreturn]] void Refuse(const ShardFile& s, const std::string& what) {
  throw UsageError("merge-datasets: " + s.label + " " + what);
}

// Checks that the shards are the whole of one run, each once; returns the merged order:
// (run index, shard, position in that shard), by run index.
std::vector<std::tuple<int, size_t, size_t>> MergedOrder(const std::vector<ShardFile>& shards) {
  const json& first = shards.front().selection;
  const int count = first.at("shard").at(1).get<int>();
  std::map<int, const ShardFile*> seen;
  for (const ShardFile& s : shards) {
    const json& sel = s.selection;
    if (sel.at("run") != first.at("run") || sel.at("keep") != first.at("keep")) {
      Refuse(s, "is a shard of another run than " + shards.front().label + " (" +
                    sel.at("run").dump() + " against " + first.at("run").dump() + ")");
    }
    if (sel.at("shard").at(1).get<int>() != count) {
      Refuse(s, "is a shard of " + std::to_string(sel.at("shard").at(1).get<int>()) + ", not of " +
                    std::to_string(count));
    }
    const int index = sel.at("shard").at(0).get<int>();
    if (seen.count(index)) {
      Refuse(s, "is shard " + std::to_string(index) + " again (also " + seen[index]->label + ")");
    }
    seen[index] = &s;
  }
  std::string missing;
  for (int i = 0; i < count; ++i) {
    if (!seen.count(i)) missing += (missing.empty() ? "" : ", ") + std::to_string(i);
  }
  if (!missing.empty()) {
    throw UsageError("merge-datasets: the run has " + std::to_string(count) +
                     " shards; missing shard(s) " + missing + " of " + std::to_string(count));
  }
  std::vector<std::tuple<int, size_t, size_t>> order;
  for (size_t s = 0; s < shards.size(); ++s) {
    const json& episodes = shards[s].selection.at("episodes");
    for (size_t j = 0; j < episodes.size(); ++j) order.emplace_back(episodes[j].get<int>(), s, j);
  }
  std::sort(order.begin(), order.end());
  return order;
}

// The merged run's selection: none for a whole run of every episode (the dataset is then the one
// the run makes unsharded), else the kept episodes of every shard.
json MergedSelection(const std::vector<ShardFile>& shards,
                     const std::vector<std::tuple<int, size_t, size_t>>& order) {
  const json& first = shards.front().selection;
  if (first.at("keep") == "all") return nullptr;
  int tried = 0;
  std::vector<int> episodes;
  for (const ShardFile& s : shards) tried += s.selection.at("tried").get<int>();
  for (const auto& [k, s, j] : order) episodes.push_back(k);
  return {{"keep", first.at("keep")}, {"run", first.at("run")},   {"tried", tried},
          {"kept", episodes.size()},  {"seed", first.at("seed")}, {"episodes", episodes}};
}

void CheckSelection(const ShardFile& s) {
  if (!s.selection.is_object() || !s.selection.contains("shard")) {
    Refuse(s,
           "records no shard of a run (its selection.shard is missing): merge-datasets joins "
           "the datasets of `--shard I/N` runs");
  }
  try {
    (void)s.selection.at("run");
    (void)s.selection.at("keep");
    (void)s.selection.at("episodes").get<std::vector<int>>();
    (void)s.selection.at("shard").get<std::array<int, 2>>();
  } catch (const std::exception&) {
    Refuse(s, "has a selection fetchscope did not write");
  }
}

H5File OpenReadOnly(const fs::path& path, const std::string& label) {
  SilenceHdf5Errors();
  H5File f(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!f)
    throw UsageError("merge-datasets: " + label + ": cannot open " + path.string() + " as HDF5");
  return f;
}

std::string StringAttribute(hid_t object, const char* name, const std::string& label) {
  std::string why;
  std::optional<std::string> text = ReadStringAttribute(object, name, &why);
  if (!text) {
    throw UsageError("merge-datasets: " + label + (why.rfind("has no", 0) == 0 ? " " : ": ") + why);
  }
  return *text;
}

int64_t Int64Attribute(hid_t object, const char* name, const std::string& label) {
  const H5Attribute a(H5Aexists(object, name) > 0 ? H5Aopen(object, name, H5P_DEFAULT) : -1);
  int64_t v = 0;
  if (!a || H5Aread(a.get(), H5T_NATIVE_INT64, &v) < 0) {
    throw UsageError("merge-datasets: " + label + " has no integer attribute " + name);
  }
  return v;
}

// Copies every shard's episodes in `order` (MergedOrder's: checked before any writer is made;
// groups PREFIX<j>, their length in attribute `length`) into
// `writer` in the run's order, gives it the merged selection and commits it.
template <class Writer>
DatasetMergeResult CopyInRunOrder(const std::vector<ShardFile>& shards,
                                  const std::vector<std::tuple<int, size_t, size_t>>& order,
                                  const std::string& prefix, const char* length, Writer* writer) {
  for (const auto& [k, s, j] : order) {
    const std::string group = prefix + std::to_string(j);
    const H5Group g(H5Gopen2(shards[s].file.get(), group.c_str(), H5P_DEFAULT));
    if (!g) Refuse(shards[s], "has no " + group + " (its selection lists more episodes)");
    writer->AddCopy(shards[s].file.get(), group,
                    Int64Attribute(g.get(), length, shards[s].label + " " + group),
                    shards[s].label);
  }
  const json selection = MergedSelection(shards, order);
  if (!selection.is_null()) writer->SetSelection(selection);
  DatasetMergeResult r;
  r.path = writer->Commit().string();
  r.shards = static_cast<int>(shards.size());
  r.episodes = static_cast<int>(order.size());
  return r;
}

}  // namespace

DatasetMergeResult MergeMinariShards(const DatasetMergeRequest& request) {
  std::vector<ShardFile> shards;
  for (const std::string& given : request.shards) {
    ShardFile s;
    s.label = given;
    const MinariLocation where = LocateMinariDataset(given, request.root);
    s.hdf5 = where.hdf5;
    const std::string text = ReadFileCapped(where.metadata, kMaxJsonFileBytes);
    ParseMinariMetadata(text, where.metadata.string());  // a Fetch dataset fetchscope reads
    s.metadata = ParsePythonJson(text);
    s.selection = s.metadata.value("selection", json());
    CheckSelection(s);
    s.file = OpenReadOnly(s.hdf5, given);
    shards.push_back(std::move(s));
  }
  if (shards.empty()) throw UsageError("merge-datasets: name the shards' datasets to merge");
  const json& m = shards.front().metadata;
  for (const ShardFile& s : shards) {
    for (const char* key : {"observation_space", "action_space", "env_spec", "pixels"}) {
      if (s.metadata.value(key, json()) != m.value(key, json())) {
        Refuse(s, std::string("has another ") + key + " than " + shards.front().label);
      }
    }
  }
  const auto order = MergedOrder(shards);
  const json env_spec = ParsePythonJson(m.at("env_spec").get<std::string>());
  MinariWriteOptions o;
  o.dataset_id = request.minari_id;
  o.root = request.root;
  o.overwrite = request.overwrite;
  o.spec = &FindEnvSpec(env_spec.at("id").get<std::string>());
  o.max_episode_steps = env_spec.at("max_episode_steps").get<int>();
  o.algorithm_name = m.value("algorithm_name", "");
  if (m.contains("author")) o.author = m["author"].at(0).get<std::string>();
  if (m.contains("author_email")) o.author_email = m["author_email"].at(0).get<std::string>();
  o.code_permalink = m.value("code_permalink", "");
  o.description = m.value("description", "");
  PixelLayout layout;
  if (m.contains("pixels")) {
    layout = PixelLayoutFromJson(m["pixels"], shards.front().label);
    o.pixels = &layout;
  }
  MinariWriter writer(o);
  return CopyInRunOrder(shards, order, "episode_", "total_steps", &writer);
}

DatasetMergeResult MergeRobomimicShards(const DatasetMergeRequest& request) {
  std::vector<ShardFile> shards;
  for (const std::string& given : request.shards) {
    ShardFile s;
    s.label = given;
    s.hdf5 = given;
    s.file = OpenReadOnly(s.hdf5, given);
    const H5Group data(H5Gopen2(s.file.get(), "data", H5P_DEFAULT));
    if (!data) Refuse(s, "has no group data: not a robomimic file");
    s.metadata = {{"env_args", StringAttribute(data.get(), "env_args", given)},
                  {"pixels", StringAttribute(data.get(), "pixels", given)}};
    try {
      s.selection = json::parse(StringAttribute(data.get(), "selection", given));
    } catch (const UsageError&) {
      s.selection = nullptr;
    } catch (const json::exception&) {
      Refuse(s, "has a selection that is not JSON");
    }
    CheckSelection(s);
    shards.push_back(std::move(s));
  }
  if (shards.empty()) throw UsageError("merge-datasets: name the shards' files to merge");
  for (const ShardFile& s : shards) {
    if (s.metadata != shards.front().metadata) {
      Refuse(s, "has another env_args or pixels layout than " + shards.front().label);
    }
  }
  const auto order = MergedOrder(shards);
  const PixelLayout layout = PixelLayoutFromJson(
      json::parse(shards.front().metadata.at("pixels").get<std::string>()), shards.front().label);
  RobomimicWriteOptions o;
  o.file = request.robomimic;
  o.overwrite = request.overwrite;
  o.pixels = &layout;
  o.valid_fraction = request.valid_fraction;
  o.env_args = shards.front().metadata.at("env_args").get<std::string>();
  RobomimicWriter writer(o);
  return CopyInRunOrder(shards, order, "data/demo_", "num_samples", &writer);
}

}  // namespace fetchscope
