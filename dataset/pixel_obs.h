// Pixel observations on their way into a dataset (docs/guide/datasets.md, "Pixel datasets").
// Workers render each step's images and compress each one on their own cores into an episode's
// staging file (PixelStagingWriter); the dataset writer, in episode order, copies the compressed
// images into its HDF5 file as they are, one image per chunk (H5Dwrite_chunk), so compression
// scales with the workers and the writer never decompresses. The staging file also carries each
// image's camera geometry and, for robomimic's `states`, each step's MuJoCo state.
#pragma once

#include <hdf5.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "dataset/hdf5_handles.h"

namespace fetchscope {

/// An image layer as a dataset stores it.
enum class ImageLayer : uint8_t {
  kRgb = 0,           ///< uint8 (H, W, 3)
  kDepth = 1,         ///< float32 (H, W), metres along the view axis, 0 = nothing hit
  kSegmentation = 2,  ///< int32 (H, W): body id, nbody + site id for a site, -1 = nothing
};

/// "rgb", "depth", "segmentation".
const char* ImageLayerName(ImageLayer layer);

/// One observed camera as the dataset describes it.
struct PixelCamera {
  std::string name;                 ///< its key
  std::string camera;               ///< the --camera value that renders it
  bool moving = false;              ///< pose stored per step (else once)
  double fovy = 0;                  ///< vertical field of view, degrees
  double fx = 0, fy = 0;            ///< focal lengths, pixels
  double cx = 0, cy = 0;            ///< principal point, pixels
  std::array<double, 7> pose = {};  ///< the pose at the first step stored (x y z qw qx qy qz)
};

/// What a pixel dataset holds besides the state.
struct PixelLayout {
  int width = 0, height = 0;            ///< pixels of every image
  std::vector<ImageLayer> layers;       ///< in the order rgb, depth, segmentation
  std::vector<PixelCamera> cameras;     ///< in the order given
  std::string overlay = "none";         ///< --obs-overlay as resolved
  nlohmann::json segmentation_legend;   ///< [{"id", "body", "site"}]: every object index
  int deflate_level = kDefaultDeflate;  ///< gzip level of every image chunk
  bool states = false;                  ///< the staging files carry MuJoCo states
  bool raw_rgb = true;                  ///< rgb staged as gzip chunks (robomimic's arrays)
  bool png_rgb = false;                 ///< rgb staged as PNG files (Minari's images)
  size_t state_size = 0;                ///< numbers per state, when they do
  /// gzip level of every image chunk: 1, chosen by measurement (BENCHMARKS.md, "Pixel
  /// datasets": depth shuffled at level 1 is 18% smaller and twice as fast as level 4 unshuffled)
  static constexpr int kDefaultDeflate = 1;

  bool has(ImageLayer layer) const;
  /// Bytes of one uncompressed image of `layer`.
  size_t ImageBytes(ImageLayer layer) const;
  /// The "cameras" description every output stores: per camera name, its camera, size, fovy,
  /// intrinsic matrix K (3x3, row-major lists), fx fy cx cy, whether it moves, and for a fixed
  /// camera its pose; with the conventions spelt out.
  nlohmann::json CamerasJson() const;
};

/// The description of a pixel dataset every output stores (Minari's metadata "pixels",
/// robomimic's data attribute "pixels"): width, height, layers, overlay, the keys of each layer,
/// CamerasJson's cameras and conventions, and the segmentation legend.
nlohmann::json PixelsJson(const PixelLayout& layout);

/// The layout PixelsJson described (merge-datasets reads a shard's back). Throws RunError naming
/// `label` where a key is missing or mistyped.
PixelLayout PixelLayoutFromJson(const nlohmann::json& pixels, const std::string& label);

/// Writes one episode's staging file. Every method throws RunError naming the file where the
/// system refuses (a full disk).
class PixelStagingWriter {
 public:
  PixelStagingWriter(const std::filesystem::path& path, int deflate_level);
  ~PixelStagingWriter();
  PixelStagingWriter(const PixelStagingWriter&) = delete;
  PixelStagingWriter& operator=(const PixelStagingWriter&) = delete;

  /// Compresses image `layer` of camera `camera` at step t (`bytes` raw bytes) and appends it.
  void AddImage(int camera, ImageLayer layer, int t, const void* raw, size_t bytes);
  /// Appends camera `camera`'s rgb image at step t as the bytes of a PNG file (Minari's images).
  void AddPng(int camera, int t, const std::string& png);
  /// Appends camera `camera`'s geometry at step t: fovy fx fy cx cy, then the pose (7).
  void AddGeometry(int camera, int t, const std::array<double, 12>& geometry);
  /// Appends the MuJoCo state at step t.
  void AddState(int t, const std::vector<double>& state);
  /// Flushes and closes the file.
  void Close();

 private:
  void Write(const void* data, size_t bytes);
  std::filesystem::path path_;
  int level_;
  std::FILE* file_ = nullptr;
  std::vector<uint8_t> compressed_;  // reused
  std::vector<uint8_t> shuffled_;    // reused
};

/// One record of a staging file, as read back.
struct StagedRecord {
  enum Kind : uint8_t { kImage = 1, kGeometry = 2, kState = 3, kPng = 4 } kind = kImage;
  int camera = 0;
  ImageLayer layer = ImageLayer::kRgb;
  int t = 0;
  std::vector<uint8_t> bytes;   ///< kImage: the compressed image (a gzip chunk's bytes); kPng
  std::vector<double> numbers;  ///< kGeometry (12) or kState
};

/// Reads staging file `path`, calling `on_record` for each record in file order. Throws
/// RunError naming the file when it is cut short or malformed.
void ReadPixelStaging(const std::filesystem::path& path,
                      const std::function<void(const StagedRecord&)>& on_record);

/// The staging file of episode `index` in `folder`.
std::filesystem::path StagingFileOf(const std::filesystem::path& folder, int index);

/// One episode's staging file, loaded: what the dataset writers copy.
struct StagedEpisode {
  /// images[camera][layer][t]: the compressed image (indexed by ImageLayer's value)
  std::vector<std::array<std::vector<std::vector<uint8_t>>, 3>> images;
  std::vector<std::vector<std::vector<uint8_t>>>
      png;  ///< [camera][t]: rgb as PNG files, where staged
  std::vector<std::vector<std::array<double, 12>>> geometry;  ///< [camera][t]
  std::vector<std::vector<double>> states;                    ///< [t], where staged
};

/// Loads `path` for an episode of `rows` steps (T+1, the reset included) of `layout`. Throws
/// RunError naming the file when an image, geometry or state (layout.states) of a step is
/// missing, or a camera or step lies outside the layout.
StagedEpisode LoadStagedEpisode(const std::filesystem::path& path, const PixelLayout& layout,
                                int rows);

/// Fills `layout`'s camera geometry (fovy, intrinsics, first pose) from step 0 of `episode`.
void FillCameraGeometry(const StagedEpisode& episode, PixelLayout* layout);

/// The (rows, 7) poses of camera `camera` of `episode` (x y z qw qx qy qz per step).
std::vector<double> CameraPoses(const StagedEpisode& episode, int camera);

/// The HDF5 type of `layer`'s pixels (file and memory: little-endian u8, f32 or i32).
hid_t ImageFileType(ImageLayer layer);

/// Creates dataset `name` in `parent` for `rows` images of `layer`, one image per chunk,
/// byte-shuffled (depth and segmentation) and gzip-compressed at `layout.deflate_level`, shape
/// (rows, H, W, 3) for rgb and (rows, H, W) for the others, or (rows, H, W, 1) with `channel_axis`
/// (robomimic's depth). Throws RunError naming `file`.
H5Dataset CreateImageDataset(hid_t parent, const char* name, const PixelLayout& layout,
                             ImageLayer layer, hsize_t rows, bool channel_axis,
                             const std::string& file);

/// Creates dataset `name` in `parent` holding `pngs` (one PNG file per step) as a 1-D
/// variable-length uint8 dataset, as Minari 0.5.3 stores an image space and decodes it with PIL.
/// Throws RunError naming `file`.
void WritePngDataset(hid_t parent, const char* name, const std::vector<std::vector<uint8_t>>& pngs,
                     const std::string& file);

/// Writes compressed image `bytes` as chunk `row` of `dataset` (H5Dwrite_chunk). Throws RunError
/// naming `file`.
void WriteImageChunk(hid_t dataset, hsize_t row, const std::vector<uint8_t>& bytes,
                     const std::string& file);

/// The description of every object index the segmentation layer can show on `model`'s bodies
/// and sites: [{"id", "body", "site"}] (site null for a body), from names in model order.
nlohmann::json SegmentationLegend(const std::vector<std::string>& bodies,
                                  const std::vector<std::pair<std::string, std::string>>& sites);

}  // namespace fetchscope
