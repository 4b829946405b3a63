// Randomized looks (issue 49): colours, procedural textures, lighting and camera jitter drawn
// once per episode and applied by the renderer to its scene only, never to mjModel or mjData,
// so a trajectory stays bitwise equal to the plain run's by construction. The user's guide
// (docs/guide/recording.md, "Randomized looks") lists the kinds, default ranges and rules.
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace fetchscope {

/// A closed range [min, max] a quantity is drawn from, uniformly.
struct LookRange {
  double min = 0;  ///< lowest value
  double max = 0;  ///< highest value
};

/// Which kinds are drawn and the ranges they are drawn from. The defaults follow robosuite's
/// DomainRandomizationWrapper (robosuite/wrappers/domain_randomization_wrapper.py and its
/// modders, as summarised in shared/reference/pixel-datasets.md); each is noted below.
struct LookConfig {
  bool colors = false;        ///< rgba of the object, table, floor (and robot links)
  bool textures = false;      ///< procedural textures on the table and floor
  bool lighting = false;      ///< the model's lights
  bool camera = false;        ///< every rendered camera's pose and fovy
  bool robot_colors = false;  ///< colours also recolour each robot0: link (off by default)

  /// colours: each rgb channel, absolute (robosuite's random rgb, drawn in [0, 1])
  LookRange color_rgb{0.0, 1.0};
  /// textures: each channel of the two colours of a texture (robosuite's rgb in [0, 1])
  LookRange texture_rgb{0.0, 1.0};
  /// textures: pattern tiles per metre of surface (a checker tile holds 2 x 2 cells)
  LookRange texture_scale{1.5, 6.0};
  /// lighting: offset of each position coordinate, metres (robosuite position_perturbation 0.1)
  LookRange light_pos{-0.1, 0.1};
  /// lighting: angle the direction turns by about a random axis, radians (robosuite
  /// direction_perturbation 0.35)
  LookRange light_dir_angle{0.0, 0.35};
  /// lighting: offset of each ambient/diffuse/specular channel, clamped to [0, 1] after
  /// (robosuite ambient/diffuse/specular perturbation 0.1)
  LookRange light_ambient{-0.1, 0.1};
  LookRange light_diffuse{-0.1, 0.1};   ///< as light_ambient
  LookRange light_specular{-0.1, 0.1};  ///< as light_ambient
  /// camera: offset of each position coordinate in the world, metres (robosuite 0.01)
  LookRange camera_pos{-0.01, 0.01};
  /// camera: angle the camera turns by about a random axis, radians (robosuite 0.087, ~5 deg)
  LookRange camera_angle{0.0, 0.087};
  /// camera: offset of the vertical field of view, degrees (robosuite 5)
  LookRange camera_fovy{-5.0, 5.0};

  bool any() const { return colors || textures || lighting || camera; }
};

/// The kinds --randomize accepts, in the order the help and errors list them.
inline constexpr const char* kLookKinds[] = {"colors", "textures", "lighting", "camera"};

/// Parses --randomize: a comma list of colors, textures, lighting, camera (each once; spaces
/// after the commas allowed), or "none" (also the empty string): the plain look. Throws
/// UsageError in one line naming the bad token and listing the accepted ones.
LookConfig ParseRandomize(const std::string& list);

/// The --randomize-config keys, in the order errors list them: "robot_colors" (true/false) and
/// one [min, max] pair of numbers per LookConfig range, named as its member.
std::vector<std::string> LookConfigKeys();

/// Reads --randomize-config FILE.json into `config` (kinds stay as --randomize set them): a JSON
/// object of LookConfigKeys() entries, each optional. Throws UsageError in one line naming the
/// file and, for an unknown key, the key and the accepted ones; for a range whose min > max, the
/// range; for a value that is not a pair of finite numbers (or not a boolean), the key.
void ReadLookConfig(const std::string& path, LookConfig* config);

/// As ReadLookConfig, for a parsed document; `where` names it in messages.
void ApplyLookConfig(const nlohmann::json& doc, const std::string& where, LookConfig* config);

/// A procedural texture of a surface: a pattern of two colours.
struct SurfaceTexture {
  std::string kind = "checker";         ///< checker, gradient or noise
  std::array<double, 3> rgb1{1, 1, 1};  ///< first colour (0..1)
  std::array<double, 3> rgb2{0, 0, 0};  ///< second colour (0..1)
  double scale = 2;                     ///< pattern tiles per metre
  uint64_t noise_seed = 0;              ///< noise: seeds the per-texel mix of the two colours
  bool operator==(const SurfaceTexture& o) const;
};

/// One model light's drawn values; a missing field keeps the model's. pos and dir are in the
/// light's body frame, as mjModel's light_pos and light_dir.
struct LightLook {
  std::optional<std::array<double, 3>> pos;       ///< metres
  std::optional<std::array<double, 3>> dir;       ///< unit vector
  std::optional<std::array<double, 3>> ambient;   ///< rgb 0..1
  std::optional<std::array<double, 3>> diffuse;   ///< rgb 0..1
  std::optional<std::array<double, 3>> specular;  ///< rgb 0..1
};

/// One rendered camera's jitter; a missing field keeps the camera's own.
struct CameraJitter {
  std::array<double, 3> dpos{0, 0, 0};  ///< position offset, metres, world frame
  /// small rotation as axis * angle (radians) in the camera frame (x right, y up, z back),
  /// turning the camera about its own position
  std::array<double, 3> drot{0, 0, 0};
  std::optional<double> fovy;  ///< vertical field of view, degrees (absolute)
};

/// The look of one episode: what DrawLook drew (or a file stored). Every map may lack entries:
/// a missing part, surface, light or camera keeps its plain look.
struct LookDraw {
  uint64_t seed = 0;  ///< the seed it was drawn from (LookSeed)
  bool colors = false, textures = false, lighting = false, camera = false;  ///< kinds drawn
  /// rgba (0..1) by part: "object", "table", "floor", and a robot0: body's name
  std::map<std::string, std::array<double, 4>> colors_by_part;
  /// by surface: "table", "floor"
  std::map<std::string, SurfaceTexture> textures_by_surface;
  std::map<int, LightLook> lights;  ///< by model light id
  /// by camera key: the --camera text of a rendered view (CameraText), e.g. "external_camera_0",
  /// "default", "track", "free:..."
  std::map<std::string, CameraJitter> cameras;
};

/// The seed of episode `episode`'s look: a generator of its own, never the env's reset
/// generator. SplitMix64 mixes a constant tag ("look"), `seed` (the episode's or the run's
/// seed) and `episode`, so that looks never correlate with the physics draws of the same seed.
uint64_t LookSeed(uint64_t seed, int episode);

/// The minimum contrast DrawLook keeps between the object and the table: the difference of
/// their relative luminance (WCAG: 0.2126 R + 0.7152 G + 0.0722 B of linearised sRGB, 0..1).
inline constexpr double kMinObjectContrast = 0.2;
/// How many times DrawLook redraws colours and textures before its fallback.
inline constexpr int kLookContrastTries = 64;

/// The relative luminance (as kMinObjectContrast) of an rgb colour in [0, 1].
double RelativeLuminance(const std::array<double, 3>& rgb);

/// The object's contrast under `draw`: the smallest luminance difference between the object's
/// colour and the table's as drawn (its rgba times each of its texture's colours; the plain
/// colours of `model`'s object0 and table0 geoms where `draw` keeps them).
double ObjectContrast(const LookDraw& draw, const mjModel* model);

/// Draws a look from `seed` for the views `camera_keys` of `model`. Deterministic: the same
/// arguments give the same draw. Each kind has its own stream (turning lighting on does not
/// change the colours) and each camera key its own (a camera's jitter does not depend on the
/// other views). Colours and textures are redrawn, up to kLookContrastTries times, until
/// ObjectContrast >= kMinObjectContrast; then the fallback: the object turns black or white,
/// whichever contrasts more, and, if still short, the table's texture turns solid (both colours
/// its first), which leaves a contrast of at least 0.5 with colours on; with colours off, the
/// table keeps its plain look (no texture).
LookDraw DrawLook(const LookConfig& config, uint64_t seed,
                  const std::vector<std::string>& camera_keys, const mjModel* model);

/// `draw` as JSON; ParseLookJson reads it back exactly (doubles as base/json_util.h writes them).
nlohmann::json LookJson(const LookDraw& draw);

/// Reads LookJson's output. Strict: throws UsageError in one line naming `where` and the key
/// path of an unknown key, a missing field or a value of the wrong type.
LookDraw ParseLookJson(const nlohmann::json& json, const std::string& where);

/// The pixels (rgb, row-major, `size` x `size`) of a texture, as the renderer uploads it.
std::vector<uint8_t> TexturePixels(const SurfaceTexture& texture, int size);

}  // namespace fetchscope
