// The view options (render/view.h) as command-line options, for the commands that render.
#pragma once

#include <CLI/CLI.hpp>

#include "render/view.h"

namespace fetchscope::cli {

/// Adds --camera, --overlay, --width, --height, --hud-position, --hud-opacity, --backend,
/// --msaa, --readback and --gpu to `sub`, bound to `options`.
void AddViewOptions(CLI::App* sub, ViewOptions* options);

}  // namespace fetchscope::cli
