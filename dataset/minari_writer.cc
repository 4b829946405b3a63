#include "dataset/minari_writer.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>  // renameat2
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <regex>
#include <system_error>

#include "base/errors.h"
#include "base/stop_signal.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

// h5py's chunk guess for chunks=True (aim at 8 KiB to 1 MiB per chunk, halving dimensions in
// turn), so our chunking is what Minari's h5py calls would have chosen
std::vector<hsize_t> GuessChunk(const std::vector<hsize_t>& shape, size_t typesize) {
  constexpr double kBase = 16 * 1024, kMin = 8 * 1024, kMax = 1024 * 1024;
  std::vector<double> chunks;
  for (hsize_t x : shape) chunks.push_back(x == 0 ? 1024.0 : static_cast<double>(x));
  auto product = [&] {
    double p = 1;
    for (double c : chunks) p *= c;
    return p;
  };
  const double dset_size = product() * static_cast<double>(typesize);
  double target = kBase * std::pow(2.0, std::log10(dset_size / (1024.0 * 1024.0)));
  target = std::min(std::max(target, kMin), kMax);
  for (size_t idx = 0;; ++idx) {
    const double bytes = product() * static_cast<double>(typesize);
    if ((bytes < target || std::fabs(bytes - target) / target < 0.5) && bytes < kMax) break;
    if (product() == 1) break;
    double& c = chunks[idx % chunks.size()];
    c = std::ceil(c / 2.0);
  }
  std::vector<hsize_t> out;
  for (double c : chunks) out.push_back(static_cast<hsize_t>(c));
  return out;
}

// Caps libhdf5's metadata cache of a file at 4 MiB (its default grows to 32 MiB): the global
// heaps that hold a pixel dataset's PNG files stay cached otherwise, episode after episode.
bool CapMetadataCache(hid_t fapl) {
  H5AC_cache_config_t config;
  config.version = H5AC__CURR_CACHE_CONFIG_VERSION;
  if (H5Pget_mdc_config(fapl, &config) < 0) return false;
  config.set_initial_size = true;
  config.initial_size = 1 << 20;
  config.max_size = 4 << 20;
  config.min_size = 1 << 20;
  return H5Pset_mdc_config(fapl, &config) >= 0;
}

// the property list every object we create uses: no access/modification timestamps, so the
// same data gives the same bytes
H5PropList NoTimesList(hid_t plist_class) {
  H5PropList plist(H5Pcreate(plist_class));
  if (plist) H5Pset_obj_track_times(plist.get(), false);
  return plist;
}

// h5py's bool: an 8-bit signed enum {FALSE = 0, TRUE = 1}
H5Datatype BoolType() {
  H5Datatype type(H5Tenum_create(H5T_NATIVE_INT8));
  const int8_t no = 0, yes = 1;
  H5Tenum_insert(type.get(), "FALSE", &no);
  H5Tenum_insert(type.get(), "TRUE", &yes);
  return type;
}

// One line for a failed libhdf5 write: the system's reason first where libhdf5 recorded one
// ("no space left on device writing FILE"), else what libhdf5 could not do.
std::string Hdf5WriteError(const std::string& file, const std::string& what) {
  std::string reason = Hdf5SystemReason();
  if (reason.empty()) return file + ": libhdf5 " + what;
  reason[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(reason[0])));
  return reason + " writing " + file + " (libhdf5 " + what + ")";
}

class EpisodeWriter {
 public:
  explicit EpisodeWriter(std::string file) : file_(std::move(file)) {}

  void Fail(const std::string& what) const {
    throw RunError(Hdf5WriteError(file_, "could not write " + what));
  }

  H5Group Group(hid_t parent, const char* name) const {
    const H5PropList gcpl = NoTimesList(H5P_GROUP_CREATE);
    H5Group group(H5Gcreate2(parent, name, H5P_DEFAULT, gcpl.get(), H5P_DEFAULT));
    if (!group) Fail(std::string("group ") + name);
    return group;
  }

  // a chunked dataset of `rows` x `cols` (cols 0: one dimension), unlimited along rows as
  // Minari's create_dataset(..., chunks=True, maxshape=(None, ...)) makes it
  void Dataset(hid_t parent, const char* name, hid_t file_type, hid_t mem_type, size_t typesize,
               hsize_t rows, hsize_t cols, const void* data) const {
    std::vector<hsize_t> dims = {rows};
    std::vector<hsize_t> maxdims = {H5S_UNLIMITED};
    if (cols) {
      dims.push_back(cols);
      maxdims.push_back(cols);
    }
    const H5Dataspace space(
        H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxdims.data()));
    const H5PropList dcpl = NoTimesList(H5P_DATASET_CREATE);
    const std::vector<hsize_t> chunk = GuessChunk(dims, typesize);
    if (!space || !dcpl ||
        H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()) < 0) {
      Fail(std::string("dataset ") + name);
    }
    const H5Dataset dset(
        H5Dcreate2(parent, name, file_type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT));
    if (!dset) Fail(std::string("dataset ") + name);
    if (rows && H5Dwrite(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0) {
      Fail(std::string("dataset ") + name);
    }
  }

  void Attribute(hid_t object, const char* name, hid_t file_type, hid_t mem_type,
                 const void* value) const {
    const H5Dataspace space(H5Screate(H5S_SCALAR));
    const H5Attribute attr(
        H5Acreate2(object, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT));
    if (!attr || H5Awrite(attr.get(), mem_type, value) < 0) {
      Fail(std::string("attribute ") + name);
    }
  }

 private:
  std::string file_;
};

void CheckRows(const MinariEpisode& e, const char* name, size_t size, size_t rows, size_t cols) {
  if (size != rows * cols) {
    throw RunError("Minari episode " + std::to_string(e.id) + ": " + name + " holds " +
                   std::to_string(size) + " values, expected " + std::to_string(rows) + " x " +
                   std::to_string(cols));
  }
}

// <root>/<id>, once the id is known to be one (before any folder is made for it)
fs::path DatasetFolder(const MinariWriteOptions& options) {
  ValidateMinariDatasetId(options.dataset_id);
  return options.root / options.dataset_id;
}

}  // namespace

namespace {

// Throws MinariInterrupted where SIGINT/SIGTERM asked to stop.
void ThrowIfStopped(const std::string& dataset_id) {
  if (const int sig = StopSignal()) {
    throw MinariInterrupted(sig, "interrupted (" +
                                     std::string(sig == SIGINT ? "SIGINT" : "SIGTERM") +
                                     ") while writing Minari dataset '" + dataset_id + "'");
  }
}

// The newest modification time of anything under `folder` (itself included).
fs::file_time_type NewestWrite(const fs::path& folder) {
  std::error_code ec;
  fs::file_time_type newest = fs::last_write_time(folder, ec);
  for (auto it = fs::recursive_directory_iterator(folder, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    newest = std::max(newest, fs::last_write_time(it->path(), ec));
  }
  return newest;
}

}  // namespace

void CheckMinariDestination(const MinariWriteOptions& options) {
  const fs::path final_path = DatasetFolder(options);
  std::error_code ec;
  if (fs::exists(fs::symlink_status(final_path, ec))) {
    if (!options.overwrite) {
      throw UsageError("Minari dataset '" + options.dataset_id + "' already exists at " +
                       final_path.string() + "; pass --overwrite to replace it");
    }
    if (!fs::is_directory(final_path / "data", ec)) {
      throw UsageError(final_path.string() +
                       " is not a Minari dataset (no data/ folder); not replacing it");
    }
  }
  // can the dataset be written there? make (and remove again) its temporary folder now, so an
  // unwritable root fails before a long run, not after it. Another task's check on the same root
  // (a Slurm array starting together) may remove an empty folder above it meanwhile: made again.
  for (int attempt = 0;; ++attempt) {
    const ParentFolders parents(final_path.string());
    const fs::path probe = TempPathFor(final_path.string());
    if (fs::create_directory(probe, ec) && !ec) {
      fs::remove(probe, ec);
      return;
    }
    if (ec == std::errc::no_such_file_or_directory && attempt < 8) continue;
    throw RunError("cannot write Minari dataset '" + options.dataset_id + "' under '" +
                   final_path.parent_path().string() +
                   "': " + (ec ? ec.message() : std::string("it exists")));
  }
}

std::vector<fs::path> RemoveStaleMinariTemps(const fs::path& final_path) {
  std::vector<fs::path> removed;
  const fs::path folder = final_path.parent_path();
  const std::regex ours("\\." +
                        std::regex_replace(final_path.filename().string(),
                                           std::regex(R"([.^$|()\[\]{}*+?\\-])"), R"(\$&)") +
                        R"(\.tmp-(\d+)-\d+)");
  std::error_code ec;
  const auto now = fs::file_time_type::clock::now();
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    std::smatch m;
    const std::string name = entry.path().filename().string();
    if (!std::regex_match(name, m, ours) || !entry.is_directory(ec)) continue;
    const long pid = std::stol(m[1].str());
    // still being written: by a process alive on this machine, or lately (another machine
    // sharing the folder, whose process ids mean nothing here)
    if (pid == getpid() || kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    if (now - NewestWrite(entry.path()) < std::chrono::minutes(1)) continue;
    if (fs::remove_all(entry.path(), ec) != static_cast<std::uintmax_t>(-1) && !ec) {
      removed.push_back(entry.path());
    }
  }
  return removed;
}

MinariWriter::MinariWriter(const MinariWriteOptions& options)
    : options_(options),
      final_path_(DatasetFolder(options)),
      temp_path_(TempPathFor(final_path_.string())),
      parents_(final_path_.string()) {
  if (!options_.spec) throw RunError("MinariWriter: no env spec");
  SilenceHdf5Errors();
  ThrowIfStopped(options_.dataset_id);
  lock_ = FolderLock::OnLockFile(
      final_path_.parent_path() / ("." + final_path_.filename().string() + ".lock"),
      "Minari dataset", options_.dataset_id);
  CheckMinariDestination(options_);
  for (const fs::path& stale : RemoveStaleMinariTemps(final_path_)) {
    std::fprintf(stderr, "removed %s, left by an interrupted dataset write\n", stale.c_str());
  }
  std::error_code ec;
  const fs::path data = temp_path_ / "data";
  if (!fs::create_directories(data, ec) || ec) {
    throw RunError("cannot create folder '" + data.string() + "': " + ec.message());
  }
  temp_exists_ = true;
  obs_dim_ = ObservationSize(options_.spec->has_object);
  if (options_.pixels) pixels_ = *options_.pixels;
  // the root group tracks and indexes creation order, as h5py's File(track_order=True)
  H5PropList fcpl = NoTimesList(H5P_FILE_CREATE);
  const unsigned order = H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED;
  if (!fcpl || H5Pset_link_creation_order(fcpl.get(), order) < 0 ||
      H5Pset_attr_creation_order(fcpl.get(), order) < 0) {
    throw RunError("libhdf5: cannot make a file creation property list");
  }
  const std::string file = (data / "main_data.hdf5").string();
  // HDF5 1.10's file format (readable by every h5py since 2.7, Minari needs h5py >= 3.8): its
  // chunk indexes for growable datasets take a few hundred bytes where the 1.8 format's B-trees
  // take kilobytes, which makes the file about 2.5 times smaller and faster to write
  H5PropList fapl(H5Pcreate(H5P_FILE_ACCESS));
  // evict each episode's metadata from libhdf5's cache once its objects are closed: memory stays
  // flat over a long run instead of growing with the cache (up to 32 MB per file)
  if (!fapl || H5Pset_libver_bounds(fapl.get(), H5F_LIBVER_V110, H5F_LIBVER_V110) < 0 ||
      H5Pset_evict_on_close(fapl.get(), true) < 0 || !CapMetadataCache(fapl.get())) {
    throw RunError("libhdf5: cannot make a file access property list");
  }
  file_ = H5File(H5Fcreate(file.c_str(), H5F_ACC_EXCL, fcpl.get(), fapl.get()));
  if (!file_) throw RunError("cannot create HDF5 file '" + file + "'");
}

MinariWriter::~MinariWriter() {
  file_.Close();
  if (temp_exists_) {
    std::error_code ec;
    fs::remove_all(temp_path_, ec);
  }
}

void MinariWriter::Add(const MinariEpisode& e, const StagedEpisode* staged) {
  if (!file_) throw RunError("MinariWriter: Add after Commit");
  if (pixels_.has_value() != (staged != nullptr)) {
    throw RunError("MinariWriter: episode " + std::to_string(e.id) +
                   (staged ? " has images the dataset does not hold" : " has no images"));
  }
  ThrowIfStopped(options_.dataset_id);
  const size_t t = e.rewards.size();
  const size_t d = static_cast<size_t>(obs_dim_);
  CheckRows(e, "observation", e.observation.size(), t + 1, d);
  CheckRows(e, "achieved_goal", e.achieved_goal.size(), t + 1, 3);
  CheckRows(e, "desired_goal", e.desired_goal.size(), t + 1, 3);
  CheckRows(e, "actions", e.actions.size(), t, 4);
  CheckRows(e, "terminations", e.terminations.size(), t, 1);
  CheckRows(e, "truncations", e.truncations.size(), t, 1);
  CheckRows(e, "is_success", e.is_success.size(), t + 1, 1);

  const EpisodeWriter w((temp_path_ / "data" / "main_data.hdf5").string());
  const std::string name = "episode_" + std::to_string(episodes_);
  const H5Group group = w.Group(file_.get(), name.c_str());
  // attributes in Minari's order: id, seed (where seeded), total_steps; a Python int becomes
  // int64 in h5py, or uint64 when it does not fit (DataCollector's 64-bit seeds)
  const int64_t id = episodes_, total_steps = static_cast<int64_t>(t);
  w.Attribute(group.get(), "id", H5T_STD_I64LE, H5T_NATIVE_INT64, &id);
  if (e.seed) {
    if (*e.seed <= static_cast<uint64_t>(INT64_MAX)) {
      const int64_t seed = static_cast<int64_t>(*e.seed);
      w.Attribute(group.get(), "seed", H5T_STD_I64LE, H5T_NATIVE_INT64, &seed);
    } else {
      w.Attribute(group.get(), "seed", H5T_STD_U64LE, H5T_NATIVE_UINT64, &*e.seed);
    }
  }
  w.Attribute(group.get(), "total_steps", H5T_STD_I64LE, H5T_NATIVE_INT64, &total_steps);
  // a randomized look's draw (--randomize), as JSON text: Minari's loader passes it over
  if (!e.look.empty() && !WriteStringAttribute(group.get(), "look", e.look)) {
    w.Fail("attribute look");
  }

  {
    const H5Group obs = w.Group(group.get(), "observations");
    w.Dataset(obs.get(), "observation", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, t + 1, d,
              e.observation.data());
    w.Dataset(obs.get(), "achieved_goal", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, t + 1, 3,
              e.achieved_goal.data());
    w.Dataset(obs.get(), "desired_goal", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, t + 1, 3,
              e.desired_goal.data());
  }
  w.Dataset(group.get(), "actions", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 4, t, 4, e.actions.data());
  if (options_.spec->dense) {  // Gymnasium-Robotics' dtypes: float64 dense, float32 sparse
    w.Dataset(group.get(), "rewards", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8, t, 0, e.rewards.data());
  } else {
    const std::vector<float> rewards(e.rewards.begin(), e.rewards.end());
    w.Dataset(group.get(), "rewards", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 4, t, 0, rewards.data());
  }
  const H5Datatype boolean = BoolType();
  w.Dataset(group.get(), "terminations", boolean.get(), boolean.get(), 1, t, 0,
            e.terminations.data());
  w.Dataset(group.get(), "truncations", boolean.get(), boolean.get(), 1, t, 0,
            e.truncations.data());
  const H5Group infos = w.Group(group.get(), "infos");
  if (staged) {
    if (episodes_ == 0) FillCameraGeometry(*staged, &*pixels_);
    const H5Group obs(H5Gopen2(group.get(), "observations", H5P_DEFAULT));
    if (!obs) w.Fail("group observations");
    AddPixels(obs.get(), infos.get(), *staged, t + 1);
  }
  w.Dataset(infos.get(), "is_success", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, 4, t + 1, 0,
            e.is_success.data());
  ++episodes_;
  steps_ += static_cast<int64_t>(t);
}

void MinariWriter::AddCopy(hid_t source, const std::string& episode, int64_t steps,
                           const std::string& label) {
  if (!file_) throw RunError("MinariWriter: Add after Commit");
  ThrowIfStopped(options_.dataset_id);
  const std::string name = "episode_" + std::to_string(episodes_);
  const std::string file = (temp_path_ / "data" / "main_data.hdf5").string();
  if (H5Ocopy(source, episode.c_str(), file_.get(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT) < 0) {
    throw RunError(Hdf5WriteError(file, "could not copy " + episode + " of " + label));
  }
  const H5Group group(H5Gopen2(file_.get(), name.c_str(), H5P_DEFAULT));
  const H5Attribute id(group ? H5Aopen(group.get(), "id", H5P_DEFAULT) : -1);
  const int64_t n = episodes_;
  if (!id || H5Awrite(id.get(), H5T_NATIVE_INT64, &n) < 0) {
    throw RunError(Hdf5WriteError(file, "could not renumber " + name));
  }
  ++episodes_;
  steps_ += steps;
}

void MinariWriter::AddPixels(hid_t observations, hid_t infos, const StagedEpisode& staged,
                             hsize_t rows) {
  const std::string file = (temp_path_ / "data" / "main_data.hdf5").string();
  const EpisodeWriter w(file);
  const PixelLayout& layout = *pixels_;
  for (ImageLayer layer : layout.layers) {
    const char* key = layer == ImageLayer::kRgb ? "images" : ImageLayerName(layer);
    const H5Group group = w.Group(observations, key);
    for (size_t c = 0; c < layout.cameras.size(); ++c) {
      if (layer == ImageLayer::kRgb) {  // PNG files: Minari 0.5.3 decodes an image space so
        WritePngDataset(group.get(), layout.cameras[c].name.c_str(), staged.png[c], file);
        continue;
      }
      const H5Dataset dset = CreateImageDataset(group.get(), layout.cameras[c].name.c_str(), layout,
                                                layer, rows, false, file);
      const auto& images = staged.images[c][static_cast<size_t>(layer)];
      for (hsize_t r = 0; r < rows; ++r) WriteImageChunk(dset.get(), r, images[r], file);
    }
  }
  bool any_moving = false;
  for (const PixelCamera& c : layout.cameras) any_moving = any_moving || c.moving;
  if (!any_moving) return;
  const H5Group poses = w.Group(infos, "camera_pose");
  for (size_t c = 0; c < layout.cameras.size(); ++c) {
    if (!layout.cameras[c].moving) continue;
    const std::vector<double> p = CameraPoses(staged, static_cast<int>(c));
    w.Dataset(poses.get(), layout.cameras[c].name.c_str(), H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 8,
              rows, 7, p.data());
  }
}

std::string MinariWriter::ObservationSpaceJson() const {
  if (!pixels_) return FetchObservationSpaceJson(obs_dim_);
  PixelSpaces spaces;
  for (const PixelCamera& c : pixels_->cameras) spaces.cameras.push_back(c.name);
  spaces.width = pixels_->width;
  spaces.height = pixels_->height;
  spaces.rgb = pixels_->has(ImageLayer::kRgb);
  spaces.depth = pixels_->has(ImageLayer::kDepth);
  spaces.segmentation = pixels_->has(ImageLayer::kSegmentation);
  spaces.max_segment = static_cast<int>(pixels_->segmentation_legend.size()) - 1;
  return FetchPixelObservationSpaceJson(obs_dim_, spaces);
}

std::string MinariWriter::MetadataJson(double dataset_size_mb) const {
  // json.dump's output of the dict create_dataset_from_buffers builds, in its key order
  std::string j = "{\"total_episodes\": " + std::to_string(episodes_) +
                  ", \"total_steps\": " + std::to_string(steps_) +
                  ", \"data_format\": \"hdf5\", \"observation_space\": " +
                  PythonJsonString(ObservationSpaceJson()) +
                  ", \"action_space\": " + PythonJsonString(FetchActionSpaceJson()) +
                  ", \"env_spec\": " +
                  PythonJsonString(FetchEnvSpecJson(*options_.spec, options_.max_episode_steps)) +
                  ", \"dataset_id\": " + PythonJsonString(options_.dataset_id);
  if (!options_.code_permalink.empty()) {
    j += ", \"code_permalink\": " + PythonJsonString(options_.code_permalink);
  }
  j += ", \"author\": [" + PythonJsonString(options_.author) + "]";
  if (!options_.author_email.empty()) {
    j += ", \"author_email\": [" + PythonJsonString(options_.author_email) + "]";
  }
  j += ", \"algorithm_name\": " + PythonJsonString(options_.algorithm_name);
  if (!options_.description.empty()) {
    j += ", \"description\": " + PythonJsonString(options_.description);
  }
  j += ", \"minari_version\": \"" + std::string(kMinariVersionWritten) + "\"";
  j += ", \"requirements\": [";
  const std::vector<std::string> requirements = FetchRequirements();
  for (size_t i = 0; i < requirements.size(); ++i) {
    j += (i ? ", " : "") + PythonJsonString(requirements[i]);
  }
  j += "]";
  if (pixels_) j += ", \"pixels\": " + PixelsJson(*pixels_).dump(-1, ' ', true);
  if (!selection_.is_null()) j += ", \"selection\": " + selection_.dump(-1, ' ', true);
  j += ", \"dataset_size\": " + nlohmann::json(dataset_size_mb).dump() + "}";
  return j;
}

fs::path MinariWriter::Commit() {
  const fs::path data = temp_path_ / "data";
  if (!file_ || !file_.Close()) {
    throw RunError(Hdf5WriteError((data / "main_data.hdf5").string(), "could not finish the file"));
  }
  std::error_code ec;
  const auto hdf5_bytes = fs::file_size(data / "main_data.hdf5", ec);
  // Minari's get_size: every file under data/ in MB (1e6 bytes), rounded half-even to 0.1
  auto size_mb = [&](size_t metadata_bytes) {
    return std::nearbyint(static_cast<double>(hdf5_bytes + metadata_bytes) / 1e6 * 10) / 10;
  };
  ThrowIfStopped(options_.dataset_id);
  const double size = size_mb(MetadataJson(size_mb(MetadataJson(0).size())).size());
  WriteFileAtomically((data / "metadata.json").string(), MetadataJson(size));

  if (fs::exists(fs::symlink_status(final_path_, ec))) {
    if (!options_.overwrite) {
      throw RunError("Minari dataset '" + options_.dataset_id + "' appeared at " +
                     final_path_.string() + " while it was being written; not replacing it");
    }
    // swap the new dataset in atomically, then remove the old one (now at the temporary name);
    // where the file system cannot swap, move the old one aside first
    if (renameat2(AT_FDCWD, temp_path_.c_str(), AT_FDCWD, final_path_.c_str(), RENAME_EXCHANGE) !=
        0) {
      const fs::path old = TempPathFor(final_path_.string());
      if (std::rename(final_path_.c_str(), old.c_str()) != 0 ||
          std::rename(temp_path_.c_str(), final_path_.c_str()) != 0) {
        throw RunError("cannot replace " + final_path_.string() + ": " + std::strerror(errno));
      }
      fs::remove_all(old, ec);
    }
  } else if (std::rename(temp_path_.c_str(), final_path_.c_str()) != 0) {
    throw RunError("cannot rename " + temp_path_.string() + " to " + final_path_.string() + ": " +
                   std::strerror(errno));
  } else {
    temp_exists_ = false;
  }
  parents_.Keep();
  fs::remove_all(temp_path_, ec);
  temp_exists_ = false;
  // Minari's create_namespace: an empty namespace_metadata.json in every namespace folder
  fs::path ns = options_.root;
  const std::string namespaces = MinariNamespace(options_.dataset_id);
  for (size_t begin = 0; begin < namespaces.size();) {
    const size_t slash = std::min(namespaces.find('/', begin), namespaces.size());
    ns /= namespaces.substr(begin, slash - begin);
    begin = slash + 1;
    const fs::path file = ns / "namespace_metadata.json";
    if (!fs::exists(file, ec)) WriteFileAtomically(file.string(), "{}");
  }
  return final_path_;
}

}  // namespace fetchscope
