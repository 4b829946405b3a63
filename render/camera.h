// Camera specs from the command line (--camera) and their MuJoCo cameras.
//
// Grammar (one or more cameras, separated by commas):
//   spec   := camera ("," camera)*
//   camera := "default" | "track" | "free" | "free:" key "=" value ("," key "=" value)*
//           | "track:" tkey "=" value ("," tkey "=" value)*
//           | NAME                                    (a camera named in the model)
//   key    := lookat (three numbers x,y,z) | distance | azimuth | elevation (degrees)
//   tkey   := body (a body of the model; robot0:gripper_link by default) | distance | azimuth
//           | elevation
// A free or track spec's own commas are told apart from list commas by what follows: a
// comma-separated token that holds '=' or is a number continues the free (or track) camera
// before it; any other token starts the next camera, as does a token that begins with "free" or
// "track". So
// "free:lookat=1,0.7,0.5,distance=2,external_camera_0" is two cameras. Missing free keys take the
// default camera's values.
#pragma once

#include <mujoco/mujoco.h>

#include <string>
#include <string_view>
#include <vector>

namespace fetchscope {

/// Pose of a free (orbiting) camera, as MuJoCo's mjCAMERA_FREE.
struct FreeCamera {
  double lookat[3];  ///< point looked at (m, world frame)
  double distance;   ///< from the lookat point (m)
  double azimuth;    ///< degrees about +z
  double elevation;  ///< degrees; negative looks down
};

/// Gymnasium's DEFAULT_CAMERA_CONFIG for the Fetch tasks.
FreeCamera DefaultFreeCamera();

/// A kind of --camera that is not one of the model's own cameras: the one list that parsing's
/// "did you mean", its accepted forms, list-cameras and the shell completion read.
struct CameraKind {
  std::string_view name;        ///< "default", "track", "free"
  std::string_view completion;  ///< what completion offers: "free:" (the keys follow)
  std::string_view listed;      ///< list-cameras' first column: "free:..."
  std::string_view summary;     ///< list-cameras' second column
  std::string_view forms;       ///< the accepted forms, for errors: "track, track:body=NAME,..."
};

/// default, track, free: in the order list-cameras prints them.
const std::vector<CameraKind>& CameraKinds();

/// One parsed camera.
struct CameraSpec {
  enum Kind {
    kDefault,  ///< Gymnasium's default free camera
    kNamed,    ///< a camera defined in the model (mjCAMERA_FIXED)
    kFree,     ///< a free camera with the given pose
    kTrack,    ///< follows a body, robot0:gripper_link by default (mjCAMERA_TRACKING)
  } kind;
  std::string name;  ///< the camera name (kNamed) or the token as written
  FreeCamera free;   ///< pose for kDefault/kFree; distance/azimuth/elevation for kTrack
  std::string body = "robot0:gripper_link";  ///< kTrack: the body followed
};

/// Parses a --camera value (grammar above). `model` supplies the camera names (may be null:
/// then no named camera is accepted). Throws UsageError naming the bad token and what is
/// accepted, listing the model's cameras when a name is unknown.
std::vector<CameraSpec> ParseCameraList(const std::string& spec, const mjModel* model);

/// The body a "track" camera follows unless it names one.
inline constexpr char kTrackBody[] = "robot0:gripper_link";

/// The --camera text of one camera that ParseCameraList reads back as `spec` (numbers with
/// up to 6 significant digits: "free:lookat=1.3,0.75,0.55,distance=2.5,azimuth=132,
/// elevation=-14"; "default"; a named camera's name; "track" for the default tracking camera,
/// else "track:body=NAME,distance=...").
std::string CameraText(const CameraSpec& spec);

/// Fills a MuJoCo camera for `spec` on `model` (which must hold the named camera/track body;
/// ParseCameraList checked that). Throws UsageError otherwise.
mjvCamera ToMjvCamera(const CameraSpec& spec, const mjModel* model);

}  // namespace fetchscope
