#include "apps/scene_options.h"

#include <CLI/CLI.hpp>

#include <string>

namespace strata::cli {

void add_scene_options(CLI::App& cmd, SceneOptions& o) {
  cmd.add_option("--walkers,-n", o.walkers, "Number of walkers on the ground grid")->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{10'000'000}));
  cmd.add_option("--motion", o.motion,
                 "What moves the walkers: 'walk' (walk generator along a track; the default), 'clip' (the "
                 "file's own animation) or FILE.bvh (motion capture retargeted onto the skeleton, feet locked by IK)");
  cmd.add_option("--skeleton", o.skeleton, "H-Anim file (X3D or paper XML); default: the shipped 25-joint skeleton");
  cmd.add_option("--mesh", o.mesh,
                 "Skinned body to animate instead of the shipped one: a glTF 2.0 file (.glb/.gltf, plays its "
                 "animation), a MakeHuman hm08 folder (base.obj + default.mhskel + default_weights.mhw; walks), "
                 "or an X3D H-Anim file with a skin (plays its interpolators)");
  cmd.add_option("--clip", o.clip, "Clip to play: a name, an index, or 'all' (default: all clips together)");
  cmd.add_flag("--rest", o.rest, "Hold the rest pose instead of playing a clip");
  cmd.add_option("--seed", o.seed, "Seed for per-walker phase, rate and heading")->capture_default_str();
  cmd.add_option("--spacing", o.spacing, "Metres between walkers on the grid")->capture_default_str();
  cmd.add_option("--threads", o.threads, "Worker threads (0 = all cores)")->capture_default_str();
  // Parsed by DetailLevel::parse, the one place that knows level names; the validator runs first so a bad value
  // is a usage error naming the flag rather than an exception from the callback.
  const CLI::Validator body_level(
      [](std::string& value) -> std::string {
        if (DetailLevel::parse(value)) return {};
        return "must be 0, 1, 2, auto, S1, S2, S3 or -1, got '" + value + "'";
      },
      "0|1|2|auto|S1|S2|S3|-1");
  cmd.add_option_function<std::string>(
         "--level", [&o](const std::string& value) { o.level = *DetailLevel::parse(value); },
         "Body resolution level: 0 (17,953 vertices), 1 (8,923), 2 (5,133); auto: each walker by its height "
         "on screen (with hysteresis); S1, S2, S3: the 1,800-vertex cage skinned and Loop-subdivided 1-3 "
         "times every frame (7,194 / 28,770 / 115,074 vertices); -1 for skeletons only")
      ->check(body_level)->default_str(o.level.name());
  cmd.add_option("--muscles", o.muscles,
                 "Muscle layer: 'default' (the shipped 12 action lines, data/muscles.json), 'none', or a muscle "
                 "file (format: io/muscle_file.h)")->capture_default_str();
  cmd.add_option("--muscle-gain", o.muscle_gain, "Scale every muscle's forces (0 = no bulge, 1 = as in the file)")
      ->capture_default_str()->check(CLI::Range(0.0f, 100.0f));
  cmd.add_option("--muscle-overrides", o.muscle_overrides,
                 "JSON file of per-muscle gains, e.g. {\"gain\": 1, \"muscles\": {\"l_biceps\": 2}}");
  cmd.add_option("--binding-overrides", o.binding_overrides,
                 "Skin binding overrides file (format: data/binding_overrides.json; e.g. saved by the binding "
                 "editor) used instead of the shipped one to bind the shipped body's levels and cage");
}

}  // namespace strata::cli
