// serve's requests, typed at the edge: every query parameter is checked here (a known name, given
// once, its value within its range or list) before anything runs, and a request that fails gets
// one line and a 4xx. Episodes are named by index, never by path; a program is never named here.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/overlay.h"
#include "render/renderer.h"

namespace fetchscope::serve {

/// A request the server refuses: the HTTP status and one line saying why (served as
/// {"error": message}).
class RequestError : public std::runtime_error {
 public:
  RequestError(int status, const std::string& message)
      : std::runtime_error(message), status_(status) {}
  int status() const { return status_; }

 private:
  int status_;
};

/// Query parameters, by name, as the HTTP library decodes them (a name may repeat: refused).
using Query = std::multimap<std::string, std::string>;

/// The longest value any parameter may have, in bytes.
inline constexpr size_t kMaxParameterBytes = 512;
/// The most pixels per side of a live frame (render's --width and --height); the whole frame
/// must also stay within render's kMaxFramePixels.
inline constexpr int kMaxFrameSideLive = 8192;

/// Which image of the view a frame request wants.
enum class ImageFormat { kJpeg, kPng };

/// A served episode's step, or the session's live episode's (source == kLiveSource).
struct StepRef {
  int source = 0;   ///< index into the served sources; kLiveSource: the session's live episode
  int episode = 0;  ///< the episode's index in its source (ignored for the live episode)
  int step = 0;     ///< t: 0 is the reset
};
inline constexpr int kLiveSource = -1;

/// What a frame (or pick) request asks to see.
struct ViewRequest {
  StepRef at;
  std::string camera = "default";  ///< --camera text, checked against the model when rendered
  int width = 640;                 ///< pixels of the view
  int height = 480;
  std::string overlay_text = "default";  ///< --overlay text, as given
  OverlaySet overlays;                   ///< what it parses to
  Layer layer = Layer::kRgb;
  ImageFormat format = ImageFormat::kJpeg;
  int quality = 80;  ///< JPEG quality
  /// the look (render/look.h): "" the episode's own (a recording's stored look, else serve's
  /// --randomize draw, else plain), "plain", "recorded" (the stored look or plain), or a seed N
  /// (a draw of serve's --randomize kinds, all four without it, from LookSeed(N, episode))
  std::string look;
};

/// A hover: which object is at pixel (x, y) of that view (row 0 = top).
struct PickRequest {
  ViewRequest view;
  int x = 0;
  int y = 0;
};

/// One live step: the action given (keys), or the command line's policy's next action.
struct StepRequest {
  std::optional<std::array<double, 4>> action;  ///< each within [-1, 1]; none: the policy acts
};

/// Where a live episode starts: a live env of the command line (its reset), or a step of a served
/// episode ("continue from this step").
struct StartRequest {
  std::optional<int> env;  ///< index of a live env (--env-id); else `from`
  StepRef from;
  /// a live env's reset placed by hand (goal=x,y,z; object=x,y or x,y,z), m in world
  /// coordinates: the seed's reset with these in place of what it drew
  std::optional<std::array<double, 3>> goal;
  std::vector<double> object;  ///< 2 or 3 numbers; empty: where the seed's reset put it
};

/// The session a request belongs to: its id as given (checked against the sessions later).
std::string SessionParam(const Query& query);

/// The requests, from their query parameters. Each throws RequestError(400) naming the parameter,
/// the value and what is accepted, for an unknown or repeated parameter, a missing one, a value
/// too long (kMaxParameterBytes), not a whole number, out of its range, or not in its list; a
/// frame larger than render accepts (sides and pixels) is refused with 413.
ViewRequest ParseViewRequest(const Query& query);
PickRequest ParsePickRequest(const Query& query);
StepRequest ParseStepRequest(const Query& query);

/// Refuses every parameter but the session (and the token) in one line (400).
void CheckNoParameters(const Query& query);

/// The `source` of a listing request (0..9999, required).
int ParseSourceRequest(const Query& query);
StartRequest ParseStartRequest(const Query& query);
/// An episode's data: its source and index.
StepRef ParseEpisodeRequest(const Query& query);

}  // namespace fetchscope::serve
