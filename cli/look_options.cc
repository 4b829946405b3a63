#include "cli/look_options.h"

#include "base/errors.h"
#include "cli/common.h"

namespace fetchscope::cli {

void AddLookOptions(CLI::App* sub, LookOptions* o, const std::string& from_note) {
  o->option = sub->add_option(
      "--randomize", o->randomize,
      "Randomized look, one draw per episode: a comma list of colors (object, table, floor), "
      "textures (checker, gradient or noise on the table and floor), lighting (the model's "
      "lights) and camera (pose and fovy jitter of every view), or none. Drawn from the seed and "
      "the episode, apart from the physics (the states are the plain run's); the draw is stored "
      "with each episode (\"look\"). Ranges: docs/guide/recording.md, \"Randomized looks\"" +
          from_note);
  sub->add_option("--look-seed", o->look_seed,
                  "--randomize: draw the looks from this seed instead of --seed (episode k's "
                  "look is LookSeed(S, k)): the same episodes under other looks");
  sub->add_option("--randomize-config", o->config,
                  "JSON file of [min, max] ranges (and robot_colors) for --randomize, e.g. "
                  "{\"camera_fovy\": [-2, 2]}; keys not given keep their defaults");
}

std::optional<LookConfig> ResolveLook(const LookOptions& o) {
  const bool given = o.option && o.option->count() > 0;
  if (!given) {
    if (!o.config.empty()) {
      throw UsageError("--randomize-config '" + o.config +
                       "' without --randomize sets ranges for nothing; accepted: with "
                       "--randomize LIST (colors, textures, lighting, camera)");
    }
    return std::nullopt;
  }
  LookConfig config = ParseRandomize(o.randomize);
  if (!o.config.empty()) ReadLookConfig(o.config, &config);
  return config;
}

std::optional<uint64_t> ResolveLookSeed(const LookOptions& o) {
  if (o.look_seed.empty()) return std::nullopt;
  if (!o.option || o.option->count() == 0) {
    throw UsageError("--look-seed " + o.look_seed +
                     " without --randomize draws nothing; accepted: with --randomize LIST");
  }
  return ParseSeed(o.look_seed);
}

}  // namespace fetchscope::cli
