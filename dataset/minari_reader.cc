#include "dataset/minari_reader.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "base/confined_file.h"
#include "base/errors.h"
#include "base/suggest.h"
#include "dataset/hdf5_handles.h"
#include "dataset/minari_format.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// the most values one array may hold (Fetch's are 51 x 25); a bigger one is refused before any
// memory is allocated for it
constexpr hsize_t kMaxValues = hsize_t{1} << 26;

[[noreturn]] void Fail(const std::string& label, const std::string& what) {
  throw RunError(label + ": " + what);
}

// libhdf5's own description of the last failure (innermost first), and clears its stack
std::string Hdf5Reason() {
  std::vector<std::string> descriptions;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned, const H5E_error2_t* error, void* data) -> herr_t {
        if (error->desc && *error->desc) {
          static_cast<std::vector<std::string>*>(data)->push_back(error->desc);
        }
        return 0;
      },
      &descriptions);
  H5Eclear2(H5E_DEFAULT);
  for (const std::string& d : descriptions) {
    if (d.find("truncated") != std::string::npos) return d;
  }
  return descriptions.empty() ? "no reason given" : descriptions.front();
}

// A regular file of at most kMaxJsonFileBytes (UsageError otherwise: a FIFO, a device, huge).
std::string ReadText(const fs::path& path) {
  try {
    return ReadFileCapped(path, kMaxJsonFileBytes);
  } catch (const RunError&) {
    Fail(path.string(),
         "cannot be read (a Minari dataset has data/metadata.json beside "
         "data/main_data.hdf5)");
  }
}

// the width of a one-dimensional Box of `dtype`, or 0 when `box` is not one
int BoxWidth(const json& box, const char* dtype) {
  if (!box.is_object() || box.value("type", json()) != "Box" || box.value("dtype", json()) != dtype)
    return 0;
  const json shape = box.value("shape", json());
  if (!shape.is_array() || shape.size() != 1 || !shape[0].is_number_integer()) return 0;
  return shape[0].get<int>();
}

// a serialised space: a JSON string holding Python JSON (Minari's serialize_space)
json SpaceJson(const std::string& label, const json& value, const char* key) {
  if (!value.is_string()) Fail(label, std::string(key) + " is not a string of serialised JSON");
  try {
    return ParsePythonJson(value.get<std::string>());
  } catch (const json::exception&) {
    Fail(label, std::string(key) + " is not valid JSON");
  }
}

int CheckObservationSpace(const std::string& label, const json& space) {
  const char* expected =
      "observation_space is not a Fetch space: expected a Dict of achieved_goal (3), "
      "desired_goal (3) and observation (10 or 25), each a float64 Box (and, in a pixel "
      "dataset, Dicts images, depth, segmentation)";
  if (!space.is_object() || space.value("type", json()) != "Dict") Fail(label, expected);
  const json subspaces = space.value("subspaces", json());
  if (!subspaces.is_object()) Fail(label, expected);
  size_t images = 0;  // a pixel dataset's image Dicts (docs/guide/datasets.md), not read here
  for (const char* key : {"images", "depth", "segmentation"}) {
    if (!subspaces.contains(key)) continue;
    if (subspaces[key].value("type", json()) != "Dict") Fail(label, expected);
    ++images;
  }
  if (subspaces.size() != 3 + images) Fail(label, expected);
  for (const char* goal : {"achieved_goal", "desired_goal"}) {
    if (!subspaces.contains(goal) || BoxWidth(subspaces[goal], "float64") != 3) {
      Fail(label, expected);
    }
  }
  const int width =
      subspaces.contains("observation") ? BoxWidth(subspaces["observation"], "float64") : 0;
  if (width <= 0 || !LayoutHasObject(static_cast<size_t>(width))) Fail(label, expected);
  return width;
}

// The reads of one episode group; every failure names the file and the episode.
class EpisodeReader {
 public:
  EpisodeReader(std::string label, hid_t group) : label_(std::move(label)), group_(group) {}

  [[noreturn]] void Fail(const std::string& what) const { fetchscope::Fail(label_, what); }

  // a dataset's handle and shape: `cols` 0 means one dimension
  H5Dataset Open(const char* name, hsize_t cols, hsize_t* rows, bool required = true) const {
    // H5Lexists fails on a path whose first part is missing, so test each part
    std::string path;
    std::istringstream parts(name);
    for (std::string part; std::getline(parts, part, '/');) {
      path += (path.empty() ? "" : "/") + part;
      if (H5Lexists(group_, path.c_str(), H5P_DEFAULT) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        if (!required) return H5Dataset();
        Fail(std::string("missing key '") + name + "'");
      }
    }
    H5Dataset dset(H5Dopen2(group_, name, H5P_DEFAULT));
    if (!dset) Fail(std::string("'") + name + "' is not a dataset (" + Hdf5Reason() + ")");
    const H5Dataspace space(H5Dget_space(dset.get()));
    const int rank = space ? H5Sget_simple_extent_ndims(space.get()) : -1;
    hsize_t dims[2] = {0, 0};
    if (rank != (cols ? 2 : 1) || H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0) {
      Fail(std::string("'") + name + "' should have " +
           (cols ? "two dimensions" : "one dimension") + ", it has " + std::to_string(rank));
    }
    if (cols && dims[1] != cols) {
      Fail(std::string("'") + name + "' has " + std::to_string(dims[1]) + " columns, expected " +
           std::to_string(cols));
    }
    if (dims[0] * std::max<hsize_t>(cols, 1) > kMaxValues) {
      Fail(std::string("'") + name + "' has " + std::to_string(dims[0]) + " rows, too many");
    }
    *rows = dims[0];
    return dset;
  }

  void ExpectRows(const char* name, hsize_t rows, hsize_t expected, const char* why) const {
    if (rows != expected) {
      Fail("episodes of the wrong length: '" + std::string(name) + "' has " + std::to_string(rows) +
           " rows, expected " + std::to_string(expected) + " (" + why + ")");
    }
  }

  // a float array (integers are accepted too, for is_success), converted by libhdf5
  template <typename T>
  std::vector<T> Numbers(const H5Dataset& dset, const char* name, hsize_t count,
                         hid_t mem_type) const {
    const H5Datatype type(H5Dget_type(dset.get()));
    const H5T_class_t cls = type ? H5Tget_class(type.get()) : H5T_NO_CLASS;
    if (cls != H5T_FLOAT && cls != H5T_INTEGER) {
      Fail(std::string("'") + name + "' does not hold numbers");
    }
    std::vector<T> values(count);
    if (count && H5Dread(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0)
      Fail(std::string("cannot read '") + name + "' (" + Hdf5Reason() + ")");
    return values;
  }

  // booleans in h5py's convention (an 8-bit enum FALSE/TRUE) or plain integers, each 0 or 1
  std::vector<uint8_t> Booleans(const H5Dataset& dset, const char* name, hsize_t count) const {
    const H5Datatype type(H5Dget_type(dset.get()));
    const H5T_class_t cls = type ? H5Tget_class(type.get()) : H5T_NO_CLASS;
    std::vector<int64_t> values(count);
    herr_t status = -1;
    if (cls == H5T_ENUM && H5Tget_size(type.get()) == 1) {
      const H5Datatype native(H5Tget_native_type(type.get(), H5T_DIR_DEFAULT));
      std::vector<int8_t> raw(count);
      status =
          count ? H5Dread(dset.get(), native.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data()) : 0;
      std::copy(raw.begin(), raw.end(), values.begin());
    } else if (cls == H5T_INTEGER) {
      status = count ? H5Dread(dset.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                               values.data())
                     : 0;
    } else {
      Fail(std::string("'") + name + "' does not hold booleans");
    }
    if (status < 0) Fail(std::string("cannot read '") + name + "' (" + Hdf5Reason() + ")");
    std::vector<uint8_t> out(count);
    for (hsize_t i = 0; i < count; ++i) {
      if (values[i] != 0 && values[i] != 1) Fail(std::string("'") + name + "' holds a non-boolean");
      out[i] = static_cast<uint8_t>(values[i]);
    }
    return out;
  }

  // an integer attribute of the group, signed or unsigned (h5py stores a Python int as int64,
  // or uint64 when it does not fit)
  std::optional<uint64_t> Unsigned(const char* name) const {
    if (H5Aexists(group_, name) <= 0) return std::nullopt;
    const H5Attribute attr(H5Aopen(group_, name, H5P_DEFAULT));
    const H5Datatype type(attr ? H5Aget_type(attr.get()) : -1);
    const H5Dataspace space(attr ? H5Aget_space(attr.get()) : -1);
    if (!type || !space || H5Tget_class(type.get()) != H5T_INTEGER ||
        H5Sget_simple_extent_npoints(space.get()) != 1) {
      Fail(std::string("attribute '") + name + "' is not one integer");
    }
    if (H5Tget_sign(type.get()) == H5T_SGN_NONE) {
      uint64_t value = 0;
      if (H5Aread(attr.get(), H5T_NATIVE_UINT64, &value) < 0)
        Fail("cannot read " + std::string(name));
      return value;
    }
    int64_t value = 0;
    if (H5Aread(attr.get(), H5T_NATIVE_INT64, &value) < 0) Fail("cannot read " + std::string(name));
    if (value < 0) Fail(std::string("attribute '") + name + "' is negative");
    return static_cast<uint64_t>(value);
  }

 private:
  std::string label_;
  hid_t group_;
};

MinariEpisode ReadEpisode(const std::string& label, hid_t file, int64_t index, int obs_dim) {
  const std::string name = "episode_" + std::to_string(index);
  const std::string where = label + ": " + name;
  if (H5Lexists(file, name.c_str(), H5P_DEFAULT) <= 0) {
    H5Eclear2(H5E_DEFAULT);
    Fail(label, "missing key '" + name + "' (metadata.json's total_episodes counts it)");
  }
  const H5Group group(H5Gopen2(file, name.c_str(), H5P_DEFAULT));
  if (!group) Fail(where, "not a group (" + Hdf5Reason() + ")");
  const EpisodeReader r(where, group.get());
  MinariEpisode e;
  e.id = index;
  e.obs_dim = obs_dim;
  e.seed = r.Unsigned("seed");
  if (H5Aexists(group.get(), "look") > 0) {  // a randomized look's draw (fetchscope --randomize)
    std::string why;
    const std::optional<std::string> look = ReadStringAttribute(group.get(), "look", &why);
    if (!look || !nlohmann::json::accept(*look)) Fail(where, "attribute look: not JSON text");
    e.look = *look;
  }

  hsize_t t = 0, rows = 0;
  const H5Dataset rewards = r.Open("rewards", 0, &t);
  e.rewards = r.Numbers<double>(rewards, "rewards", t, H5T_NATIVE_DOUBLE);
  const char* obs_why = "T+1: the reset and one per step";
  struct Obs {
    const char* name;
    hsize_t cols;
    std::vector<double>* out;
  } obs[] = {{"observations/observation", static_cast<hsize_t>(obs_dim), &e.observation},
             {"observations/achieved_goal", 3, &e.achieved_goal},
             {"observations/desired_goal", 3, &e.desired_goal}};
  for (const Obs& o : obs) {
    const H5Dataset dset = r.Open(o.name, o.cols, &rows);
    r.ExpectRows(o.name, rows, t + 1, obs_why);
    *o.out = r.Numbers<double>(dset, o.name, rows * o.cols, H5T_NATIVE_DOUBLE);
  }
  const H5Dataset actions = r.Open("actions", 4, &rows);
  r.ExpectRows("actions", rows, t, "T: one per step");
  e.actions = r.Numbers<float>(actions, "actions", rows * 4, H5T_NATIVE_FLOAT);
  for (const char* key : {"terminations", "truncations"}) {
    const H5Dataset dset = r.Open(key, 0, &rows);
    r.ExpectRows(key, rows, t, "T: one per step");
    (key[1] == 'e' ? e.terminations : e.truncations) = r.Booleans(dset, key, rows);
  }
  if (const H5Dataset s = r.Open("infos/is_success", 0, &rows, false); s) {
    r.ExpectRows("infos/is_success", rows, t + 1, obs_why);
    e.is_success = r.Numbers<float>(s, "infos/is_success", rows, H5T_NATIVE_FLOAT);
  }
  // a NaN or an infinity would be stepped into MuJoCo ("unstable") and written to JSON as a
  // string: refused here, naming where it is (rows of observations: the reset, then one per step)
  auto check = [&](const char* field, const auto& values, hsize_t cols, bool has_reset) {
    for (size_t i = 0; i < values.size(); ++i) {
      if (std::isfinite(static_cast<double>(values[i]))) continue;
      const size_t row = i / cols, col = i % cols;
      const std::string at = has_reset
                                 ? (row == 0 ? "the reset" : "step " + std::to_string(row - 1))
                                 : "step " + std::to_string(row);
      std::ostringstream value;
      value << values[i];
      r.Fail(at + ": " + field + (cols > 1 ? "[" + std::to_string(col) + "]" : "") + " is " +
             value.str() + "; a replay needs finite numbers");
    }
  };
  for (const Obs& o : obs) check(o.name, *o.out, o.cols, true);
  check("actions", e.actions, 4, false);
  check("rewards", e.rewards, 1, false);
  if (const auto steps = r.Unsigned("total_steps"); steps && *steps != t) {
    r.Fail("episodes of the wrong length: attribute total_steps is " + std::to_string(*steps) +
           " but 'rewards' has " + std::to_string(t) + " rows");
  }
  return e;
}

}  // namespace

MinariLocation LocateMinariDataset(const std::string& what, const fs::path& root) {
  const auto in = [](const fs::path& data) {
    return MinariLocation{data / "main_data.hdf5", data / "metadata.json"};
  };
  std::error_code ec;
  const fs::path p(what);
  if (fs::is_regular_file(p, ec)) return {p, p.parent_path() / "metadata.json"};
  if (fs::is_directory(p, ec)) {
    if (fs::exists(p / "data", ec)) return in(p / "data");
    if (fs::exists(p / "main_data.hdf5", ec) || fs::exists(p / "metadata.json", ec)) return in(p);
    throw UsageError(what +
                     ": a folder, but not a Minari dataset (it holds neither data/ nor "
                     "main_data.hdf5)");
  }
  // an id names a folder under the root, never outside it (the writers' rule): a dataset
  // elsewhere is given by its path
  if (IsMinariDatasetId(what) && fs::is_directory(root / what / "data", ec)) {
    return in(root / what / "data");
  }
  if (!IsMinariDatasetId(what)) {
    throw UsageError("no Minari dataset '" + what +
                     "': not a file or folder, and not a dataset id ((namespace/)name-vN of "
                     "letters, digits, '-' and '_', looked up under " +
                     root.string() + "); give a dataset outside the datasets root by its path");
  }
  throw UsageError("no Minari dataset '" + what + "': not a file or folder, nor an id under " +
                   root.string() + " (--minari-root, $MINARI_DATASETS_PATH, ~/.minari/datasets)" +
                   DidYouMean(what, ListLocalMinariIds(root)));
}

std::vector<std::string> ListLocalMinariIds(const fs::path& root) {
  std::vector<std::string> ids;
  std::error_code ec;
  auto it = fs::recursive_directory_iterator(root, ec);
  for (; !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const fs::path& p = it->path();
    if (!it->is_directory(ec)) continue;
    if (p.filename().string().front() == '.' || p.filename() == "data") {
      it.disable_recursion_pending();  // temporary folders of writes; a dataset's own data/
      continue;
    }
    // a dataset's folder holds data/; one without its metadata.json is listed too (a reader
    // then says what is wrong with it) rather than left out
    if (fs::is_directory(p / "data", ec)) {
      ids.push_back(fs::relative(p, root, ec).generic_string());
      it.disable_recursion_pending();
    }
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

namespace {

// The env_spec of a dataset's metadata (none: null), its id a Fetch env's, into `m`.
const EnvSpec* ReadEnvSpec(const std::string& label, const json& j, MinariMetadata* m) {
  const EnvSpec* env = nullptr;
  if (j.contains("env_spec") && !j["env_spec"].is_null()) {
    const json spec = SpaceJson(label, j["env_spec"], "env_spec");
    if (!spec.is_object() || !spec.contains("id") || !spec["id"].is_string()) {
      Fail(label, "missing key 'id' in env_spec");
    }
    const std::string id = spec["id"];
    std::string ids;
    for (const EnvSpec& s : AllEnvSpecs()) {
      if (s.id == id) env = &s;
      ids += (ids.empty() ? "" : ", ") + s.id;
    }
    if (!env) Fail(label, "env_spec id '" + id + "' is not a Fetch environment (" + ids + ")");
    m->env_id = id;
    if (spec.value("entry_point", json()).is_string()) m->entry_point = spec["entry_point"];
    if (spec.value("max_episode_steps", json()).is_number_integer()) {
      m->max_episode_steps = spec["max_episode_steps"].get<int>();
    }
    const json kwargs = spec.value("kwargs", json());
    if (kwargs.is_object() && kwargs.value("reward_type", json()).is_string()) {
      m->reward_type = kwargs["reward_type"].get<std::string>();
    }
  }
  return env;
}

// The observation and action spaces: a Fetch env's (of `env`, when given), from the metadata
// or, without them, from the env; `m` gets the observation's width.
void CheckSpaces(const std::string& label, const json& j, const EnvSpec* env, MinariMetadata* m) {
  const int env_width = env ? ObservationSize(env->has_object) : 0;
  if (j.contains("observation_space")) {
    m->obs_dim =
        CheckObservationSpace(label, SpaceJson(label, j["observation_space"], "observation_space"));
    if (env && m->obs_dim != env_width) {
      Fail(label, "observation_space has " + std::to_string(m->obs_dim) +
                      " observation values but " + *m->env_id + " has " +
                      std::to_string(env_width));
    }
  } else if (env) {
    m->obs_dim = env_width;  // Minari then takes the spaces from the env, as we do
  } else {
    Fail(label, "missing key 'observation_space' (and no env_spec to take it from)");
  }
  if (j.contains("action_space")) {
    const json action = SpaceJson(label, j["action_space"], "action_space");
    if (BoxWidth(action, "float32") != 4) {
      Fail(label, "action_space is not a Fetch space: expected a float32 Box of shape [4]");
    }
  } else if (!env) {
    Fail(label, "missing key 'action_space' (and no env_spec to take it from)");
  }
}

}  // namespace

MinariMetadata ParseMinariMetadata(const std::string& text, const std::string& label) {
  json j;
  try {
    j = ParsePythonJson(text);
  } catch (const json::exception&) {
    Fail(label, "not valid JSON");
  }
  if (!j.is_object()) Fail(label, "not a JSON object");
  const auto need = [&](const char* key) -> const json& {
    if (!j.contains(key)) Fail(label, std::string("missing key '") + key + "'");
    return j[key];
  };
  const auto count = [&](const char* key) {
    const json& v = need(key);
    if (!v.is_number_integer() || v.get<int64_t>() < 0) {
      Fail(label, std::string(key) + " is not a count");
    }
    return v.get<int64_t>();
  };
  MinariMetadata m;
  const json& version = need("minari_version");
  m.minari_version = version.is_string() ? version.get<std::string>() : version.dump();
  if (!IsSupportedMinariVersion(m.minari_version)) {
    Fail(label, "unsupported minari_version '" + m.minari_version +
                    "' (Minari 0.5 reads datasets of 0.4.0-0.4.3 and 0.5.0-0.5.3)");
  }
  const json& format = need("data_format");
  if (format != "hdf5") {
    Fail(label, "data_format " + format.dump() + " is not supported (only \"hdf5\")");
  }
  m.total_episodes = count("total_episodes");
  m.total_steps = count("total_steps");
  if (j.contains("dataset_id") && j["dataset_id"].is_string()) m.dataset_id = j["dataset_id"];
  if (j.contains("code_permalink") && j["code_permalink"].is_string()) {
    m.code_permalink = j["code_permalink"];
  }
  if (j.contains("algorithm_name") && j["algorithm_name"].is_string()) {
    m.algorithm_name = j["algorithm_name"];
  }
  const EnvSpec* env = ReadEnvSpec(label, j, &m);
  CheckSpaces(label, j, env, &m);
  return m;
}

std::vector<MinariEpisode> ReadMinariEpisodes(const std::string& label,
                                              const MinariMetadata& metadata,
                                              const std::vector<int64_t>& indices,
                                              const std::string* image) {
  SilenceHdf5Errors();
  H5PropList fapl(H5Pcreate(H5P_FILE_ACCESS));
  if (image) {
    // a file image in memory (the fuzzer): the core driver, reading a private copy
    if (!fapl || H5Pset_fapl_core(fapl.get(), 1 << 16, false) < 0 ||
        H5Pset_file_image(fapl.get(), const_cast<char*>(image->data()), image->size()) < 0) {
      Fail(label, "libhdf5 cannot open a file image");
    }
  }
  const H5File file(H5Fopen(label.c_str(), H5F_ACC_RDONLY, fapl.get()));
  if (!file) {
    const std::string reason = Hdf5Reason();
    if (reason.find("truncated") != std::string::npos) {
      Fail(label, "truncated HDF5 file (" + reason + ")");
    }
    Fail(label, "not a readable HDF5 file (" + reason + ")");
  }
  std::vector<int64_t> all;
  if (indices.empty()) {
    for (int64_t i = 0; i < metadata.total_episodes; ++i) all.push_back(i);
  }
  std::vector<MinariEpisode> episodes;
  for (int64_t i : indices.empty() ? all : indices) {
    if (i < 0 || i >= metadata.total_episodes) {
      throw UsageError(label + ": no episode " + std::to_string(i) + " (the dataset has " +
                       std::to_string(metadata.total_episodes) + ")");
    }
    episodes.push_back(ReadEpisode(label, file.get(), i, metadata.obs_dim));
  }
  return episodes;
}

MinariDataset ReadMinariDataset(const std::string& what, const fs::path& root,
                                const std::vector<int64_t>& indices) {
  MinariDataset d;
  d.location = LocateMinariDataset(what, root);
  d.metadata = ParseMinariMetadata(ReadText(d.location.metadata), d.location.metadata.string());
  std::error_code ec;
  if (!fs::is_regular_file(d.location.hdf5, ec)) {
    Fail(d.location.hdf5.string(), "missing (a Minari dataset has data/main_data.hdf5)");
  }
  d.episodes = ReadMinariEpisodes(d.location.hdf5.string(), d.metadata, indices);
  if (indices.empty()) {
    int64_t steps = 0;
    for (const MinariEpisode& e : d.episodes) steps += e.steps();
    if (steps != d.metadata.total_steps) {
      Fail(d.location.metadata.string(),
           "total_steps is " + std::to_string(d.metadata.total_steps) + " but the episodes hold " +
               std::to_string(steps) + " steps");
    }
  }
  return d;
}

}  // namespace fetchscope
