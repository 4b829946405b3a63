#include "dataset/robomimic_writer.h"

#include <cmath>
#include <cstdio>
#include <system_error>

#include "base/errors.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

struct Writer {
  std::string file;

  [[noreturn]] void Fail(const std::string& what) const {
    const std::string reason = Hdf5SystemReason();
    throw RunError((reason.empty() ? "" : reason + " writing ") + file +
                   ": libhdf5 could not write " + what);
  }
  H5Group Group(hid_t parent, const std::string& name) const {
    H5PropList gcpl(H5Pcreate(H5P_GROUP_CREATE));
    if (gcpl) H5Pset_obj_track_times(gcpl.get(), false);
    H5Group g(H5Gcreate2(parent, name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT));
    if (!g) Fail("group " + name);
    return g;
  }
  // a contiguous dataset of `dims`, as robomimic's scripts write actions, states, rewards, dones
  void Dataset(hid_t parent, const std::string& name, hid_t type, hid_t mem,
               const std::vector<hsize_t>& dims, const void* data) const {
    const H5Dataspace space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
    H5PropList dcpl(H5Pcreate(H5P_DATASET_CREATE));
    if (dcpl) H5Pset_obj_track_times(dcpl.get(), false);
    const H5Dataset d(
        H5Dcreate2(parent, name.c_str(), type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT));
    if (!d || H5Dwrite(d.get(), mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) Fail(name);
  }
  void Int64Attribute(hid_t object, const char* name, int64_t value) const {
    const H5Dataspace space(H5Screate(H5S_SCALAR));
    const H5Attribute a(
        H5Acreate2(object, name, H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT));
    if (!a || H5Awrite(a.get(), H5T_NATIVE_INT64, &value) < 0)
      Fail(std::string("attribute ") + name);
  }
  // a variable-length UTF-8 string attribute, as h5py writes a Python str
  void StringAttribute(hid_t object, const char* name, const std::string& value) const {
    if (!WriteStringAttribute(object, name, value)) Fail(std::string("attribute ") + name);
  }
  // names as fixed-length ASCII bytes, as np.array(names, dtype='S') makes them
  void Names(hid_t parent, const std::string& name, const std::vector<std::string>& names) const {
    size_t width = 1;
    for (const std::string& n : names) width = std::max(width, n.size());
    std::string packed(width * names.size(), '\0');
    for (size_t i = 0; i < names.size(); ++i) packed.replace(i * width, names[i].size(), names[i]);
    const H5Datatype type(H5Tcopy(H5T_C_S1));
    H5Tset_size(type.get(), width);
    H5Tset_strpad(type.get(), H5T_STR_NULLPAD);
    Dataset(parent, name, type.get(), type.get(), {names.size()}, packed.data());
  }
};

// rows [first, first + count) of a (rows x cols) row-major array
std::vector<double> Rows(const std::vector<double>& values, size_t cols, size_t first,
                         size_t count) {
  return std::vector<double>(values.begin() + static_cast<long>(first * cols),
                             values.begin() + static_cast<long>((first + count) * cols));
}

}  // namespace

std::string RobomimicEnvArgs(const EnvSpec& spec, int max_episode_steps) {
  if (max_episode_steps <= 0) max_episode_steps = spec.max_episode_steps;
  return "{\n    \"env_name\": " + PythonJsonString(spec.id) +
         ",\n    \"type\": 2,\n    \"env_kwargs\": {\n        \"reward_type\": \"" +
         (spec.dense ? "dense" : "sparse") +
         "\",\n        \"max_episode_steps\": " + std::to_string(max_episode_steps) + "\n    }\n}";
}

std::vector<int> ValidDemos(int demos, double fraction) {
  std::vector<int> valid;
  for (int i = 0; i < demos; ++i) {
    if (std::floor((i + 1) * fraction) > std::floor(i * fraction)) valid.push_back(i);
  }
  return valid;
}

void CheckRobomimicDestination(const RobomimicWriteOptions& options) {
  const std::string name = options.file.filename().string();
  const auto ends = [&](const std::string& ext) {
    return name.size() > ext.size() && name.compare(name.size() - ext.size(), ext.size(), ext) == 0;
  };
  if (!ends(".hdf5") && !ends(".h5")) {
    throw UsageError("--robomimic '" + options.file.string() +
                     "': name the HDF5 file to write, ending in .hdf5 or .h5");
  }
  std::error_code ec;
  if (fs::exists(fs::symlink_status(options.file, ec))) {
    if (!options.overwrite) {
      throw UsageError("--robomimic: '" + options.file.string() +
                       "' already exists; pass --overwrite to replace it");
    }
    if (!fs::is_regular_file(options.file, ec)) {
      throw UsageError("--robomimic: '" + options.file.string() +
                       "' is not a file; not replacing it");
    }
  }
  AtomicFile probe(options.file.string());  // the folder can be written (removed uncommitted)
}

RobomimicWriter::RobomimicWriter(const RobomimicWriteOptions& options)
    : options_(options), parents_(options.file.string()) {
  if ((!options_.spec && options_.env_args.empty()) || !options_.pixels) {
    throw RunError("RobomimicWriter: no env spec or no layout");
  }
  CheckRobomimicDestination(options_);
  SilenceHdf5Errors();
  pixels_ = *options_.pixels;
  temp_ = TempPathFor(options_.file.string());
  H5PropList fcpl(H5Pcreate(H5P_FILE_CREATE));
  if (fcpl) H5Pset_obj_track_times(fcpl.get(), false);
  H5PropList fapl(H5Pcreate(H5P_FILE_ACCESS));
  if (fapl) H5Pset_evict_on_close(fapl.get(), true);  // flat memory over a long run
  file_ = H5File(H5Fcreate(temp_.c_str(), H5F_ACC_EXCL, fcpl.get(), fapl.get()));
  if (!file_) throw RunError("cannot create HDF5 file '" + temp_ + "'");
  data_ = Writer{temp_}.Group(file_.get(), "data");
}

RobomimicWriter::~RobomimicWriter() {
  data_.Close();
  file_.Close();
  if (!temp_.empty()) std::remove(temp_.c_str());
}

void RobomimicWriter::Add(const MinariEpisode& e, const StagedEpisode& staged) {
  const Writer w{temp_};
  const size_t n = static_cast<size_t>(e.steps()), d = static_cast<size_t>(e.obs_dim);
  if (demos_ == 0) FillCameraGeometry(staged, &pixels_);
  const H5Group demo = w.Group(data_.get(), "demo_" + std::to_string(demos_));
  w.Int64Attribute(demo.get(), "num_samples", static_cast<int64_t>(n));
  if (!e.look.empty()) w.StringAttribute(demo.get(), "look", e.look);  // --randomize's draw
  const std::vector<double> actions(e.actions.begin(), e.actions.end());
  w.Dataset(demo.get(), "actions", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n, 4}, actions.data());
  std::vector<double> states;
  for (size_t t = 0; t < n; ++t)
    states.insert(states.end(), staged.states[t].begin(), staged.states[t].end());
  w.Dataset(demo.get(), "states", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n, pixels_.state_size},
            states.data());
  w.Dataset(demo.get(), "rewards", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n}, e.rewards.data());
  // robomimic's done_mode 2: done at a success and at the end of the demo
  std::vector<int64_t> dones(n, 0);
  for (size_t t = 0; t < n; ++t) {
    dones[t] =
        t + 1 == n || e.terminations[t] || (!e.is_success.empty() && e.is_success[t + 1] > 0);
  }
  w.Dataset(demo.get(), "dones", H5T_STD_I64LE, H5T_NATIVE_INT64, {n}, dones.data());
  for (int next = 0; next <= (options_.next_obs ? 1 : 0); ++next) {
    const H5Group obs = w.Group(demo.get(), next ? "next_obs" : "obs");
    const size_t first = static_cast<size_t>(next);
    const auto low_dim = [&](const char* key, const std::vector<double>& v, size_t cols) {
      const std::vector<double> rows = Rows(v, cols, first, n);
      w.Dataset(obs.get(), key, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {n, cols}, rows.data());
    };
    low_dim("observation", e.observation, d);
    low_dim("achieved_goal", e.achieved_goal, 3);
    low_dim("desired_goal", e.desired_goal, 3);
    for (size_t c = 0; c < pixels_.cameras.size(); ++c) {
      const PixelCamera& cam = pixels_.cameras[c];
      for (ImageLayer layer : pixels_.layers) {
        const std::string key =
            cam.name +
            (layer == ImageLayer::kRgb ? "_image" : "_" + std::string(ImageLayerName(layer)));
        const H5Dataset dset = CreateImageDataset(obs.get(), key.c_str(), pixels_, layer, n,
                                                  layer != ImageLayer::kRgb, temp_);
        const auto& images = staged.images[c][static_cast<size_t>(layer)];
        for (size_t t = 0; t < n; ++t) WriteImageChunk(dset.get(), t, images[first + t], temp_);
      }
      if (cam.moving)
        low_dim((cam.name + "_camera_pose").c_str(), CameraPoses(staged, static_cast<int>(c)), 7);
    }
  }
  ++demos_;
  total_ += static_cast<int64_t>(n);
}

void RobomimicWriter::AddCopy(hid_t source, const std::string& demo, int64_t samples,
                              const std::string& label) {
  const std::string name = "demo_" + std::to_string(demos_);
  if (H5Ocopy(source, demo.c_str(), data_.get(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0) {
    Writer{temp_}.Fail(demo + " of " + label + " (copying it)");
  }
  ++demos_;
  total_ += samples;
}

fs::path RobomimicWriter::Commit() {
  const Writer w{temp_};
  w.Int64Attribute(data_.get(), "total", total_);
  w.StringAttribute(data_.get(), "env_args",
                    options_.env_args.empty()
                        ? RobomimicEnvArgs(*options_.spec, options_.max_episode_steps)
                        : options_.env_args);
  w.StringAttribute(data_.get(), "pixels", PixelsJson(pixels_).dump(4));
  if (!selection_.is_null()) w.StringAttribute(data_.get(), "selection", selection_.dump(4));
  if (options_.valid_fraction > 0) {
    const std::vector<int> valid = ValidDemos(demos_, options_.valid_fraction);
    std::vector<std::string> train_names, valid_names;
    size_t v = 0;
    for (int i = 0; i < demos_; ++i) {
      const bool is_valid = v < valid.size() && valid[v] == i;
      v += is_valid;
      (is_valid ? valid_names : train_names).push_back("demo_" + std::to_string(i));
    }
    const H5Group mask = w.Group(file_.get(), "mask");
    w.Names(mask.get(), "train", train_names);
    w.Names(mask.get(), "valid", valid_names);
  }
  data_.Close();
  if (!file_.Close()) w.Fail("the file (closing it)");
  CommitTempFile(temp_, options_.file.string());
  temp_.clear();
  parents_.Keep();
  return options_.file;
}

}  // namespace fetchscope
