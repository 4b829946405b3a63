// The image layers beyond rgb (render/renderer.h's Layer) as files show them: their names, the
// depth layer's grey scale, and the segmentation layer's legend (--layers is parsed in
// cli/view_options.h).
#pragma once

#include <mujoco/mujoco.h>

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace fetchscope {

/// A layer's name as --layers, the file names and the manifest write it: "rgb", "depth",
/// "segmentation".
const char* LayerName(Layer layer);

/// render -o's file for `layer` when `listed` layers are asked for: with one layer, `output`
/// itself; with several, `output` for rgb and NAME_<layer>.png for the others (-o NAME.png), as
/// record names episode_NNN.mp4 and episode_NNN_depth.mp4. The name never depends on which
/// other layers are listed, only on how many.
std::string LayerFilePath(const std::string& output, Layer layer, size_t listed);

/// render -o's segmentation legend: NAME_segmentation_legend.json for -o NAME.png, wherever
/// the segmentation image goes (record: episode_NNN_segmentation_legend.json).
std::string LegendFilePath(const std::string& output);

/// The --layers list the manifest and --resume compare: "rgb" and `layers` (those beyond rgb)
/// in order, e.g. "rgb,depth".
std::string LayersLabel(const std::vector<Layer>& layers);

/// The depth video's grey scale for one camera's view in one episode, fixed from the episode's
/// reset frame so that a shade means the same distance all episode long: `near_mm` (the nearest
/// depth in the view, rounded down to 10 cm) is white, `far_mm` (the farthest, rounded up) dark
/// grey 32; nearer is clamped to white, farther to 32, and no depth (sky, nothing hit) is black.
struct DepthScale {
  int x = 0;        ///< the view's left column in the frame, pixels
  int y = 0;        ///< the view's top row in the frame, pixels (row 0 at the top)
  int width = 0;    ///< the view's width, pixels
  int height = 0;   ///< the view's height, pixels
  int near_mm = 0;  ///< depth shown white (and anything nearer), millimetres
  int far_mm = 0;   ///< depth shown grey 32 (and anything farther), millimetres
};

/// One scale per view of the frame (`tiles`: the renderer's, bottom-left origin), from `depth`
/// (RenderLayer's millimetres of a `frame_width` x `frame_height` frame). A view with no depth
/// at all gets 0..10 m.
std::vector<DepthScale> ScalesFromFrame(const std::vector<uint8_t>& depth, int frame_width,
                                        int frame_height, const std::vector<mjrRect>& tiles);

/// Depth in millimetres (RenderLayer's uint16) -> grey rgb (`rgb`: depth.size() / 2 * 3 bytes),
/// each view with its scale; pixels in no view (the empty cells of a grid) stay black.
void DepthToGrey(const std::vector<uint8_t>& depth, int frame_width,
                 const std::vector<DepthScale>& scales, uint8_t* rgb);

/// One object of a segmentation legend (render's and record's): its colour as "#rrggbb" and as
/// rgb, body, geoms, site (null for a body) and pixels.
nlohmann::json SegmentObjectJson(const SegmentObject& object);

/// One episode's segmentation legend: every object seen in any of its frames, with the pixels
/// of all frames summed, the frames it appears in, and the geoms seen.
class EpisodeLegend {
 public:
  /// Adds one frame's objects (Renderer::segmentation_legend() after its RenderLayer).
  void Add(const std::vector<SegmentObject>& frame);

  /// The legend JSON of episode `episode`: objects by palette index, each as SegmentObjectJson
  /// plus "frames"; the colour of each object is the same in every episode, camera and run.
  nlohmann::json Json(int episode) const;

  /// Frames added so far.
  int frames() const { return frames_; }

 private:
  struct Entry {
    SegmentObject object;
    std::set<std::string> geoms;
    int frames = 0;
  };
  std::map<int, Entry> objects_;  // by palette index
  int frames_ = 0;
};

}  // namespace fetchscope
