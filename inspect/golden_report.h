// What `golden check` and `golden update` report besides their table: a JUnit XML file (one
// testcase per scene, as GitHub and GitLab show test results), a JSON file, and an HTML review
// page (index.html in the output folder: each failing or changed scene's golden, actual and
// diff image under a colour scale, a box around the changed region).
#pragma once

#include <string>
#include <vector>

#include "inspect/golden_scene.h"
#include "inspect/image_diff.h"

namespace fetchscope {

/// A rectangle of the frame, pixels, row 0 at the top; empty when width is 0.
struct ChangedRegion {
  int x = 0;
  int y = 0;
  int width = 0;
  int height = 0;
};

/// The smallest rectangle holding every pixel whose largest channel difference exceeds
/// `threshold` (or, when none does, every pixel that differs at all); empty for equal images.
ChangedRegion FindChangedRegion(const uint8_t* golden, const uint8_t* actual, int width, int height,
                                int threshold);

/// One scene's outcome.
struct GoldenRow {
  std::string scene;
  std::string status = "pass";     ///< pass | fail | error (cannot be checked) | skipped
  std::string verdict;             ///< "ok", the layer that changed, or why it cannot be checked
  std::vector<std::string> notes;  ///< assets changed, msaa capped, metadata missing, ...
  std::string state_change;        ///< named state differences ("object_pos.z +2.00 mm at t=0")
  bool have_pixels = false;        ///< pixels compared
  ImageDiffStats stats;
  GoldenTolerance tolerance;  ///< the tolerance used
  std::string tolerance_why;  ///< "same backend", "cross-backend (...)", "--tolerance"
  int width = 0;              ///< frame size
  int height = 0;
  ChangedRegion region;  ///< where the pixels changed
  /// image files under the output folder, "" when not written
  std::string golden_png, actual_png, diff_png, side_png;
  double badness = 0;  ///< how far over its limits, for sorting worst first
  double seconds = 0;  ///< time the scene took
};

/// A whole check or update.
struct GoldenRun {
  std::string command;     ///< "check" or "update"
  std::string manifest;    ///< path of manifest.json
  std::string running_on;  ///< "BACKEND / GL_RENDERER"
  std::string out;         ///< the folder of the images and the review page
  std::vector<GoldenRow> rows;
};

/// Prints the table of `rows` in their order: scene, result (ok, FAIL, ERROR or skip), the share
/// of pixels over the threshold and its limit, the largest difference, the RMS and its limit, the
/// verdict; then each row's named state change and notes (all but the missing-metadata one, which
/// the caller says once).
void PrintGoldenTable(const std::vector<GoldenRow>& rows);

/// Writes the JUnit XML report to `path` (whole or not at all): one testsuite "fetchscope golden
/// <command>", one testcase per scene, a <failure> for a failed scene (its verdict; the notes,
/// numbers and image paths in the text), an <error> for one that cannot be checked, <skipped/>.
void WriteGoldenJunit(const std::string& path, const GoldenRun& run);

/// Writes the JSON report to `path`: {"command", "manifest", "running_on", "passed", "failed",
/// "errors", "skipped", "scenes": [{"scene", "status", "verdict", "notes", "state_change",
/// "pixels": {...}, "tolerance": {...}, "changed_region", "images": {...}}]}.
void WriteGoldenJson(const std::string& path, const GoldenRun& run);

/// Writes `out`/index.html and `out`/diff_scale.png: each row that is not a pass (check) or
/// that changed (update), with its images, the scale of the diff heat map and a box around the
/// changed region; a line for each scene that passed. Returns the page's path.
std::string WriteGoldenReviewPage(const std::string& out, const GoldenRun& run);

}  // namespace fetchscope
