#include "dataset/pixel_obs.h"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>

#include "base/errors.h"
#include "dataset/minari_format.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

// "no space left on device": strerror's reason as the middle of a line
std::string Reason(int err) {
  std::string r = std::strerror(err);
  if (!r.empty()) r[0] = static_cast<char>(std::tolower(static_cast<unsigned char>(r[0])));
  return r;
}

constexpr char kMagic[8] = {'F', 'S', 'P', 'I', 'X', '0', '0', '1'};

// Fixed-size record head: kind, layer, camera, t, payload bytes (host byte order: a staging file
// never leaves the machine that wrote it).
struct RecordHead {
  uint8_t kind;
  uint8_t layer;
  uint16_t camera;
  uint32_t t;
  uint64_t bytes;
};

}  // namespace

const char* ImageLayerName(ImageLayer layer) {
  switch (layer) {
    case ImageLayer::kRgb:
      return "rgb";
    case ImageLayer::kDepth:
      return "depth";
    case ImageLayer::kSegmentation:
      return "segmentation";
  }
  return "?";
}

bool PixelLayout::has(ImageLayer layer) const {
  for (ImageLayer l : layers) {
    if (l == layer) return true;
  }
  return false;
}

size_t PixelLayout::ImageBytes(ImageLayer layer) const {
  const size_t pixels = static_cast<size_t>(width) * static_cast<size_t>(height);
  return layer == ImageLayer::kRgb ? pixels * 3 : pixels * 4;
}

nlohmann::json PixelLayout::CamerasJson() const {
  nlohmann::json cams = nlohmann::json::array();
  for (const PixelCamera& c : cameras) {
    nlohmann::json j;
    j["name"] = c.name;
    j["camera"] = c.camera;
    j["width"] = width;
    j["height"] = height;
    j["fovy"] = c.fovy;
    j["fx"] = c.fx;
    j["fy"] = c.fy;
    j["cx"] = c.cx;
    j["cy"] = c.cy;
    j["K"] = {{c.fx, 0.0, c.cx}, {0.0, c.fy, c.cy}, {0.0, 0.0, 1.0}};
    j["moving"] = c.moving;
    if (!c.moving) j["pose"] = c.pose;
    cams.push_back(std::move(j));
  }
  nlohmann::json out;
  out["cameras"] = std::move(cams);
  out["conventions"] =
      "pose: camera frame in the world as x y z qw qx qy qz (MuJoCo: the camera looks along its "
      "-z, +y up; OpenCV's frame is this one turned by pi about x); K: pixel centres at "
      "integers, u right, v down; depth: metres along the view axis, 0 = nothing hit; "
      "segmentation: body id, nbody + site id for a site, -1 = nothing";
  return out;
}

nlohmann::json PixelsJson(const PixelLayout& layout) {
  nlohmann::json j = layout.CamerasJson();
  j["width"] = layout.width;
  j["height"] = layout.height;
  nlohmann::json layers = nlohmann::json::array();
  for (ImageLayer l : layout.layers) layers.push_back(ImageLayerName(l));
  j["layers"] = std::move(layers);
  j["overlay"] = layout.overlay;
  j["gzip_level"] = layout.deflate_level;
  if (layout.has(ImageLayer::kSegmentation)) j["segmentation_legend"] = layout.segmentation_legend;
  return j;
}

PixelLayout PixelLayoutFromJson(const nlohmann::json& j, const std::string& label) {
  PixelLayout layout;
  try {
    layout.width = j.at("width").get<int>();
    layout.height = j.at("height").get<int>();
    for (const auto& l : j.at("layers")) {
      const std::string name = l.get<std::string>();
      if (name == "rgb")
        layout.layers.push_back(ImageLayer::kRgb);
      else if (name == "depth")
        layout.layers.push_back(ImageLayer::kDepth);
      else if (name == "segmentation")
        layout.layers.push_back(ImageLayer::kSegmentation);
      else
        throw RunError("unknown layer '" + name + "'");
    }
    layout.overlay = j.at("overlay").get<std::string>();
    layout.deflate_level = j.at("gzip_level").get<int>();
    if (j.contains("segmentation_legend")) layout.segmentation_legend = j["segmentation_legend"];
    for (const auto& c : j.at("cameras")) {
      PixelCamera cam;
      cam.name = c.at("name").get<std::string>();
      cam.camera = c.at("camera").get<std::string>();
      cam.moving = c.at("moving").get<bool>();
      cam.fovy = c.at("fovy").get<double>();
      cam.fx = c.at("fx").get<double>();
      cam.fy = c.at("fy").get<double>();
      cam.cx = c.at("cx").get<double>();
      cam.cy = c.at("cy").get<double>();
      if (!cam.moving) cam.pose = c.at("pose").get<std::array<double, 7>>();
      layout.cameras.push_back(std::move(cam));
    }
  } catch (const std::exception& e) {
    throw RunError(label + ": its pixels description is not one fetchscope wrote (" +
                   std::string(e.what()) + ")");
  }
  return layout;
}

PixelStagingWriter::PixelStagingWriter(const fs::path& path, int deflate_level)
    : path_(path), level_(deflate_level) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) {
    throw RunError("cannot create " + path.string() + ": " + std::strerror(errno));
  }
  Write(kMagic, sizeof(kMagic));
}

PixelStagingWriter::~PixelStagingWriter() {
  if (file_) std::fclose(file_);
}

void PixelStagingWriter::Write(const void* data, size_t bytes) {
  if (!file_) throw RunError(path_.string() + ": written after Close");
  if (bytes && std::fwrite(data, 1, bytes, file_) != bytes) {
    throw RunError(Reason(errno) + " writing " + path_.string());
  }
}

void PixelStagingWriter::AddImage(int camera, ImageLayer layer, int t, const void* raw,
                                  size_t bytes) {
  // depth and segmentation: 4-byte values, byte-shuffled first as HDF5's shuffle filter does
  // (byte j of value i goes to j * n + i), which the dataset declares before deflate
  const Bytef* input = static_cast<const Bytef*>(raw);
  if (layer != ImageLayer::kRgb) {
    const size_t n = bytes / 4;
    shuffled_.resize(bytes);
    for (size_t i = 0; i < n; ++i) {
      for (size_t j = 0; j < 4; ++j) shuffled_[j * n + i] = input[i * 4 + j];
    }
    input = shuffled_.data();
  }
  uLongf size = compressBound(static_cast<uLong>(bytes));
  compressed_.resize(size);
  if (compress2(compressed_.data(), &size, input, static_cast<uLong>(bytes), level_) != Z_OK) {
    throw RunError(path_.string() + ": zlib could not compress an image");
  }
  const RecordHead head{StagedRecord::kImage, static_cast<uint8_t>(layer),
                        static_cast<uint16_t>(camera), static_cast<uint32_t>(t), size};
  Write(&head, sizeof(head));
  Write(compressed_.data(), size);
}

void PixelStagingWriter::AddPng(int camera, int t, const std::string& png) {
  const RecordHead head{StagedRecord::kPng, static_cast<uint8_t>(ImageLayer::kRgb),
                        static_cast<uint16_t>(camera), static_cast<uint32_t>(t), png.size()};
  Write(&head, sizeof(head));
  Write(png.data(), png.size());
}

void PixelStagingWriter::AddGeometry(int camera, int t, const std::array<double, 12>& geometry) {
  const RecordHead head{StagedRecord::kGeometry, 0, static_cast<uint16_t>(camera),
                        static_cast<uint32_t>(t), sizeof(geometry)};
  Write(&head, sizeof(head));
  Write(geometry.data(), sizeof(geometry));
}

void PixelStagingWriter::AddState(int t, const std::vector<double>& state) {
  const RecordHead head{StagedRecord::kState, 0, 0, static_cast<uint32_t>(t),
                        state.size() * sizeof(double)};
  Write(&head, sizeof(head));
  Write(state.data(), state.size() * sizeof(double));
}

void PixelStagingWriter::Close() {
  if (!file_) return;
  const bool flushed = std::fflush(file_) == 0;
  const int err = errno;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!flushed || !closed) {
    throw RunError(Reason(flushed ? errno : err) + " writing " + path_.string());
  }
}

void ReadPixelStaging(const fs::path& path,
                      const std::function<void(const StagedRecord&)>& on_record) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw RunError("cannot read " + path.string() + ": " + std::strerror(errno));
  struct Closer {
    std::FILE* f;
    ~Closer() { std::fclose(f); }
  } closer{f};
  char magic[sizeof(kMagic)];
  if (std::fread(magic, 1, sizeof(magic), f) != sizeof(magic) ||
      std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) {
    throw RunError(path.string() + ": not an image staging file of this fetchscope");
  }
  StagedRecord record;
  RecordHead head;
  const auto cut_short = [&] { return RunError(path.string() + ": cut short"); };
  size_t n = 0;
  while ((n = std::fread(&head, 1, sizeof(head), f)) == sizeof(head)) {
    if (head.kind < StagedRecord::kImage || head.kind > StagedRecord::kPng ||
        head.layer > static_cast<uint8_t>(ImageLayer::kSegmentation) || head.bytes > (1ull << 32)) {
      throw RunError(path.string() + ": malformed record");
    }
    record.kind = static_cast<StagedRecord::Kind>(head.kind);
    record.layer = static_cast<ImageLayer>(head.layer);
    record.camera = head.camera;
    record.t = static_cast<int>(head.t);
    if (record.kind == StagedRecord::kImage || record.kind == StagedRecord::kPng) {
      record.bytes.resize(head.bytes);
      if (std::fread(record.bytes.data(), 1, head.bytes, f) != head.bytes) throw cut_short();
    } else {
      if (head.bytes % sizeof(double)) throw RunError(path.string() + ": malformed record");
      record.numbers.resize(head.bytes / sizeof(double));
      if (std::fread(record.numbers.data(), 1, head.bytes, f) != head.bytes) throw cut_short();
    }
    on_record(record);
  }
  if (n != 0 || std::ferror(f)) throw cut_short();
}

StagedEpisode LoadStagedEpisode(const fs::path& path, const PixelLayout& layout, int rows) {
  StagedEpisode e;
  const size_t cams = layout.cameras.size();
  e.images.resize(cams);
  for (auto& layers : e.images) {
    for (ImageLayer l : layout.layers) {
      if (l != ImageLayer::kRgb || layout.raw_rgb) layers[static_cast<size_t>(l)].resize(rows);
    }
  }
  if (layout.png_rgb && layout.has(ImageLayer::kRgb)) {
    e.png.assign(cams, std::vector<std::vector<uint8_t>>(rows));
  }
  e.geometry.assign(cams, std::vector<std::array<double, 12>>(rows));
  std::vector<std::vector<bool>> have_geometry(cams, std::vector<bool>(rows, false));
  if (layout.states) e.states.resize(rows);
  ReadPixelStaging(path, [&](const StagedRecord& r) {
    if (r.t < 0 || r.t >= rows ||
        (r.kind != StagedRecord::kState &&
         (r.camera < 0 || static_cast<size_t>(r.camera) >= cams))) {
      throw RunError(path.string() + ": a record of step " + std::to_string(r.t) + " or camera " +
                     std::to_string(r.camera) + " outside the episode");
    }
    if (r.kind == StagedRecord::kImage) {
      auto& steps = e.images[r.camera][static_cast<size_t>(r.layer)];
      if (steps.empty()) throw RunError(path.string() + ": a layer the dataset does not hold");
      steps[r.t] = r.bytes;
    } else if (r.kind == StagedRecord::kPng) {
      if (e.png.empty()) throw RunError(path.string() + ": a PNG the dataset does not hold");
      e.png[r.camera][r.t] = r.bytes;
    } else if (r.kind == StagedRecord::kGeometry && r.numbers.size() == 12) {
      std::copy(r.numbers.begin(), r.numbers.end(), e.geometry[r.camera][r.t].begin());
      have_geometry[r.camera][r.t] = true;
    } else if (r.kind == StagedRecord::kState && layout.states) {
      e.states[r.t] = r.numbers;
    }
  });
  for (size_t c = 0; c < cams; ++c) {
    for (int t = 0; t < rows; ++t) {
      bool complete = have_geometry[c][t];
      for (const auto& steps : e.images[c])
        complete = complete && (steps.empty() || !steps[t].empty());
      if (!e.png.empty()) complete = complete && !e.png[c][t].empty();
      if (!complete) {
        throw RunError(path.string() + ": camera " + layout.cameras[c].name +
                       " has no image of step " + std::to_string(t));
      }
    }
  }
  for (int t = 0; layout.states && t < rows; ++t) {
    if (e.states[t].size() != layout.state_size) {
      throw RunError(path.string() + ": no MuJoCo state of step " + std::to_string(t));
    }
  }
  return e;
}

void FillCameraGeometry(const StagedEpisode& episode, PixelLayout* layout) {
  for (size_t c = 0; c < layout->cameras.size() && c < episode.geometry.size(); ++c) {
    if (episode.geometry[c].empty()) continue;
    const std::array<double, 12>& g = episode.geometry[c][0];
    PixelCamera& cam = layout->cameras[c];
    cam.fovy = g[0];
    cam.fx = g[1];
    cam.fy = g[2];
    cam.cx = g[3];
    cam.cy = g[4];
    std::copy(g.begin() + 5, g.end(), cam.pose.begin());
  }
}

std::vector<double> CameraPoses(const StagedEpisode& episode, int camera) {
  std::vector<double> poses;
  for (const std::array<double, 12>& g : episode.geometry.at(camera)) {
    poses.insert(poses.end(), g.begin() + 5, g.end());
  }
  return poses;
}

fs::path StagingFileOf(const fs::path& folder, int index) {
  return folder / ("episode_" + std::to_string(index) + ".pix");
}

hid_t ImageFileType(ImageLayer layer) {
  switch (layer) {
    case ImageLayer::kRgb:
      return H5T_STD_U8LE;
    case ImageLayer::kDepth:
      return H5T_IEEE_F32LE;
    case ImageLayer::kSegmentation:
      return H5T_STD_I32LE;
  }
  return H5T_STD_U8LE;
}

H5Dataset CreateImageDataset(hid_t parent, const char* name, const PixelLayout& layout,
                             ImageLayer layer, hsize_t rows, bool channel_axis,
                             const std::string& file) {
  std::vector<hsize_t> dims = {rows, static_cast<hsize_t>(layout.height),
                               static_cast<hsize_t>(layout.width)};
  if (layer == ImageLayer::kRgb) {
    dims.push_back(3);
  } else if (channel_axis) {
    dims.push_back(1);
  }
  std::vector<hsize_t> maxdims = dims, chunk = dims;
  maxdims[0] = H5S_UNLIMITED;
  chunk[0] = 1;
  const H5Dataspace space(
      H5Screate_simple(static_cast<int>(dims.size()), dims.data(), maxdims.data()));
  H5PropList dcpl(H5Pcreate(H5P_DATASET_CREATE));
  // 4-byte values: HDF5's shuffle filter before deflate (the staging writer shuffled them)
  if (!space || !dcpl || H5Pset_obj_track_times(dcpl.get(), false) < 0 ||
      H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data()) < 0 ||
      (layer != ImageLayer::kRgb && H5Pset_shuffle(dcpl.get()) < 0) ||
      H5Pset_deflate(dcpl.get(), static_cast<unsigned>(layout.deflate_level)) < 0) {
    throw RunError(file + ": libhdf5 could not make image dataset " + name);
  }
  H5Dataset dset(H5Dcreate2(parent, name, ImageFileType(layer), space.get(), H5P_DEFAULT,
                            dcpl.get(), H5P_DEFAULT));
  if (!dset) {
    const std::string reason = Hdf5SystemReason();
    throw RunError((reason.empty() ? "" : reason + " writing ") + file +
                   ": libhdf5 could not make image dataset " + name);
  }
  return dset;
}

void WriteImageChunk(hid_t dataset, hsize_t row, const std::vector<uint8_t>& bytes,
                     const std::string& file) {
  int rank = 0;
  {
    const H5Dataspace space(H5Dget_space(dataset));
    rank = H5Sget_simple_extent_ndims(space.get());
  }
  hsize_t offset[4] = {row, 0, 0, 0};
  if (rank < 1 || rank > 4 ||
      H5Dwrite_chunk(dataset, H5P_DEFAULT, 0, offset, bytes.size(), bytes.data()) < 0) {
    const std::string reason = Hdf5SystemReason();
    throw RunError((reason.empty() ? "" : reason + " writing ") + file +
                   ": libhdf5 could not write image " + std::to_string(row));
  }
}

void WritePngDataset(hid_t parent, const char* name, const std::vector<std::vector<uint8_t>>& pngs,
                     const std::string& file) {
  const hsize_t rows = pngs.size(), maxrows = H5S_UNLIMITED;
  const hsize_t chunk = std::max<hsize_t>(1, std::min<hsize_t>(rows, 1024));
  const H5Dataspace space(H5Screate_simple(1, &rows, &maxrows));
  const H5Datatype type(H5Tvlen_create(H5T_STD_U8LE));
  H5PropList dcpl(H5Pcreate(H5P_DATASET_CREATE));
  const auto fail = [&] {
    const std::string reason = Hdf5SystemReason();
    return RunError((reason.empty() ? "" : reason + " writing ") + file +
                    ": libhdf5 could not write images " + name);
  };
  if (!space || !type || !dcpl || H5Pset_obj_track_times(dcpl.get(), false) < 0 ||
      H5Pset_chunk(dcpl.get(), 1, &chunk) < 0) {
    throw fail();
  }
  const H5Dataset dset(
      H5Dcreate2(parent, name, type.get(), space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT));
  std::vector<hvl_t> rows_data(rows);
  for (hsize_t i = 0; i < rows; ++i) {
    rows_data[i].len = pngs[i].size();
    rows_data[i].p = const_cast<uint8_t*>(pngs[i].data());
  }
  if (!dset || (rows && H5Dwrite(dset.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                 rows_data.data()) < 0)) {
    throw fail();
  }
}

nlohmann::json SegmentationLegend(const std::vector<std::string>& bodies,
                                  const std::vector<std::pair<std::string, std::string>>& sites) {
  nlohmann::json legend = nlohmann::json::array();
  int id = 0;
  for (const std::string& body : bodies) {
    legend.push_back({{"id", id++}, {"body", body}, {"site", nullptr}});
  }
  for (const auto& [body, site] : sites) {
    legend.push_back({{"id", id++}, {"body", body}, {"site", site}});
  }
  return legend;
}

}  // namespace fetchscope
