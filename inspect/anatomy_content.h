// What each panel of the anatomy card shows (inspect/anatomy_card.h draws it): the markers
// (arrows, lines, a bracket between world points), the labels and the points they name, the
// translucent spheres and the fingers' detail view, all from the reset observation of
// FetchReach-v4 or FetchPush-v4.
#pragma once

#include <string>
#include <vector>

#include "render/text.h"
#include "render/vec.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope {

/// Colours of the card: white (captions, the shell radius, the detail's ring) and the dark of
/// the label boxes and of the rims of everything drawn.
inline constexpr Rgb kCardWhite{255, 255, 255};
inline constexpr Rgb kCardDark{20, 20, 28};

/// How a marker is drawn.
enum class CardMarkerKind {
  kArrow,    ///< from -> to with a head at `to`
  kLine,     ///< plain line
  kBracket,  ///< a dimension line with end ticks
};

/// One thing drawn in 2D over the frame, between two world points.
struct CardMarker {
  std::string name;  ///< for the sidecar: what it draws
  CardMarkerKind kind;
  Vec3 from, to;  ///< world, m
  Rgb color;
  bool thin = false;  ///< a thin line (extension lines)
};

/// A label and the 3D points it may name; the placer picks the best of `at`.
struct CardLabel {
  std::string text;
  std::vector<Vec3> at;  ///< world, m
  Rgb color;
  double direction;  ///< preferred side of the anchor, degrees in the image (0 right, 90 down)
  bool dot = true;   ///< mark the anchor with a dot (not where it is an arrow's tip or a line)
};

/// A translucent sphere added to the scene.
struct CardSphere {
  Vec3 at;        ///< world, m
  double radius;  ///< m
  Rgb color;
  float alpha;
};

/// The markers and labels of one panel, from the reset observation. The fingers are small in
/// the main view: they have a magnified detail view of their own, placed beside it, with their
/// labels inside it.
struct CardContent {
  std::vector<CardSphere> spheres;         ///< translucent scene geoms
  std::vector<CardMarker> markers;         ///< drawn in 2D over the main view, in this order
  std::vector<CardLabel> labels;           ///< placed in this order
  std::vector<CardMarker> detail_markers;  ///< drawn over the detail view
  std::vector<CardLabel> detail_labels;    ///< placed inside the detail view
  std::vector<Vec3> detail_keep;           ///< what the detail's labels should leave uncovered
  Vec3 detail_at;                          ///< what the detail view looks at
  double detail_distance;                  ///< from how far, m
  Vec3 detail_across;                      ///< the line it looks across (the fingers')
  std::vector<Vec3> points;                ///< what the camera must show
  std::string footer;                      ///< the slices without a place in the scene
  std::string action_note;                 ///< what the arrows' length means
};

/// The panel of `env` (Reach or Push: by whether it has an object) in the state of `reset`;
/// `view_up` is the camera's up (world), so that the shell's radius line ends on its outline.
/// The labels name the observation's slices and indices as src/observation_layout.h lays them out.
CardContent PanelContentFor(const FetchEnv& env, const StepRecord& reset, const Vec3& view_up);

}  // namespace fetchscope
