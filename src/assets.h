// Where the MJCF comes from: bundled models, a Gymnasium-Robotics assets folder, or auto.
#pragma once

#include <string>

#include "src/env_spec.h"

namespace fetchscope {

/// A resolved assets choice, recorded in every output.
struct AssetSource {
  std::string kind;       ///< "bundled" or "dir"
  std::string root;       ///< absolute folder: bundled models/, or the envs/assets folder
  std::string fetch_dir;  ///< folder holding reach.xml, push.xml, ... (root or root/fetch)
  std::string sha256;     ///< hash of the asset files (see Sha256OfTree)
  std::string origin;     ///< how it was chosen, e.g. "--assets auto: $FETCHSCOPE_ASSETS"
};

/// Resolves `--assets bundled|auto|DIR`. auto = $FETCHSCOPE_ASSETS, else an installed
/// gymnasium_robotics package's envs/assets, else bundled. Throws UsageError for a folder that
/// does not exist or does not hold fetch/*.xml.
AssetSource ResolveAssets(const std::string& spec);

/// The model file of a task inside the source.
std::string ModelPath(const AssetSource& assets, const EnvSpec& spec);

/// The bundled models folder: <binary dir>/models, else the source tree's models/.
std::string BundledModelsDir();

/// A folder installed with the binary ("golden", "examples"): <binary dir>/NAME (a build folder,
/// the bundle's bin/, `cmake --install`'s bin/), else <binary dir>/../share/fetchscope/NAME;
/// "" when neither exists.
std::string InstalledDataDir(const std::string& name);

}  // namespace fetchscope
