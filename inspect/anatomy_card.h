// The anatomy card: a labelled Reach frame and a labelled Push frame that show where each
// observation slice and each action component lives (what each panel shows:
// inspect/anatomy_content.h).
//
// Each panel is rendered with two translucent scene geoms (the success shell, the object's
// halo); everything else is drawn in 2D (render/canvas.h) over the rendered pixels after
// projecting its 3D points (render/projection.h), so that no arrow or axis hides inside the
// robot. The fingers, a few pixels wide in the main view, get a magnified detail view of their
// own (ringed in the main view) with the finger-width bracket and the a[3] arrows. LabelPlacer
// (render/label_placer.h) puts every label inside its panel, off the other labels, leaders,
// anchor dots and markers, and never lets a leader cross another label. Text, lines, arrow
// heads, spacing and the detail view scale with the panel, so a larger card is the same card,
// sharper; below 480 x 360 the text would be under 10 px.
#pragma once

#include <cstdint>
#include <string>

#include "inspect/anatomy_content.h"
#include "render/gl_context.h"
#include "render/renderer.h"

namespace fetchscope {

/// The smallest panel: 10 px text, the smallest that stays legible, and room for every label.
inline constexpr int kAnatomyMinPanelWidth = 480;
inline constexpr int kAnatomyMinPanelHeight = 360;
/// The largest panel side.
inline constexpr int kAnatomyMaxPanelSize = 4096;

/// What the card shows and how it is rendered.
struct AnatomyCardOptions {
  uint64_t seed = 0;               ///< reset(seed=...) of both panels
  std::string seed_text = "0";     ///< the seed as given: the title and the sidecar show it
  std::string assets = "bundled";  ///< as ResolveAssets takes it (the sidecar shows it)
  int width = 720;                 ///< each panel, pixels (kAnatomyMinPanelWidth and up)
  int height = 540;                ///< pixels (kAnatomyMinPanelHeight and up)
  int msaa_samples = kMsaaAuto;    ///< RenderOptions::msaa_samples
  std::string msaa = "auto";       ///< --msaa as given, for the sidecar
};

/// Renders the card on `gl` and writes DIR/ch01_anatomy.png (Reach | Push) and
/// DIR/ch01_anatomy_labels.json (each label's text, box and leader and each marker's ends, in
/// pixels), printing a "wrote" line for each. Throws RunError when a label finds no room.
void WriteAnatomyCard(const std::string& dir, const AnatomyCardOptions& options, GlContext& gl);

}  // namespace fetchscope
