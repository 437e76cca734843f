#include "apps/scene_options.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "apps/cli_support.h"

#include <algorithm>
#include <filesystem>
#include <string>

#include "io/load_error.h"
#include "scene/input_formats.h"

namespace strata::cli {

void add_input_limit_option(CLI::App& cmd) {
  cmd.add_option_function<double>(
         "--max-input-mb",
         [](double mb) { set_input_size_limit(static_cast<std::uint64_t>(mb * 1024.0 * 1024.0)); },
         "Largest input file read, in MiB (default 1024); larger files are refused before reading")
      ->check(positive_up_to(1024.0 * 1024.0));
}

void check_scene_inputs(const SceneOptions& o) {
  auto check = [](const std::string& flag, const std::string& path, bool directory_ok) {
    if (path.empty()) return;
    try {
      check_input_path(path, directory_ok);
    } catch (const LoadError& e) {
      throw LoadError(flag + ": " + e.what());
    }
  };
  check("--skeleton", o.skeleton, false);
  check("--mesh", o.mesh, true);  // a MakeHuman folder is a directory
  if (std::filesystem::path(o.motion).has_extension()) check("--motion", o.motion, false);
  check("--retarget-map", o.retarget_map, false);
  if (o.muscles != "default" && o.muscles != "none") check("--muscles", o.muscles, false);
  check("--muscle-overrides", o.muscle_overrides, false);
  check("--binding-overrides", o.binding_overrides, false);
}

std::uint64_t estimate_crowd_bytes(const SceneOptions& o) {
  // Vertices per walker of the shipped body's levels and of the cage refined S1-S3 (docs/skin.md); under auto
  // walkers spread over the levels, so the coarsest counts.
  constexpr std::uint64_t kMeshVertices[] = {17'953, 8'923, 5'133};
  constexpr std::uint64_t kSubdivVertices[] = {1'800, 7'194, 28'770, 115'074};
  std::uint64_t vertices = 0;
  if (o.mesh.empty() && o.skeleton.empty() && !o.level.is_none()) {
    if (o.level.is_mesh()) vertices = kMeshVertices[std::min(o.level.index(), 2)];
    else if (o.level.is_subdiv()) vertices = kSubdivVertices[std::min(o.level.index(), 3)];
    else vertices = kMeshVertices[2];
  }
  // Skinned storage: position and normal, 6 floats per vertex. Joint state: world and skinning matrices, local
  // rotations and the IK and gait columns, about 50 floats for each of the 25 joints.
  constexpr std::uint64_t kJointBytes = 25 * 50 * sizeof(float);
  const std::uint64_t walkers = o.walkers;
  const bool walking = o.motion.empty() || o.motion == "walk";
  if (o.level.is_impostor()) return walkers * kJointBytes;  // no skinned storage; culled walkers keep wide rows
  if (o.level.is_automatic() && walking && o.mesh_budget > 0 && vertices > 0) {
    // At most mesh_budget walkers are skinned (at level 0 at worst); the others are impostors or culled.
    const std::uint64_t meshes = std::min<std::uint64_t>(walkers, o.mesh_budget);
    return meshes * kMeshVertices[0] * 6 * sizeof(float) + walkers * kJointBytes;
  }
  return walkers * (vertices * 6 * sizeof(float) + kJointBytes);
}

std::string check_crowd_memory(const SceneOptions& o) {
  const std::string why = check_memory(estimate_crowd_bytes(o), std::to_string(o.walkers) + " walkers at --level " +
                                                                    o.level.name());
  return why.empty() ? why : why + "; use fewer --walkers or a coarser --level";
}

nlohmann::json scene_inputs_json(const SceneOptions& o) {
  auto file = [](const std::string& path) { return path.empty() ? nlohmann::json(nullptr) : nlohmann::json(path); };
  return {{"skeleton", file(o.skeleton)},
          {"mesh", file(o.mesh)},
          {"motion", file(o.motion)},  // null: walk when the skeleton can, else its clips
          {"retarget_map", file(o.retarget_map)},
          {"muscles", o.muscles},
          {"skinning", skinning_mode_name(o.skinning)},
          {"muscle_overrides", file(o.muscle_overrides)},
          {"binding_overrides", file(o.binding_overrides)},
          {"body", shipped_body_name(o.body)}};
}

void add_scene_options(CLI::App& cmd, SceneOptions& o) {
  add_input_limit_option(cmd);
  cmd.add_option("--walkers,-n", o.walkers,
                 "Number of walkers on the ground grid (with --scenario: scales the scenario's groups to about "
                 "this many agents)")
      ->capture_default_str()->check(whole_in(1, 10'000'000, true))
      ->each([&o](const std::string&) { o.walkers_given = true; });
  cmd.add_option("--scenario", o.scenario,
                 "Crowd scenario: a shipped one (circle, crossing, bottleneck, plaza, track) or a scenario JSON "
                 "file (docs/scenarios.md): agents with goals that navigate around obstacles and avoid each other");
  cmd.add_option("--motion", o.motion,
                 "What moves the walkers: 'walk' (walk generator along a track; the default), 'clip' (the "
                 "file's own animation) or FILE.bvh (motion capture retargeted onto the skeleton, feet locked by IK)");
  cmd.add_option("--retarget-map", o.retarget_map,
                 "With --motion FILE.bvh: a text file of 'BVH_JOINT H-ANIM_JOINT' rows mapping a capture whose joint "
                 "names are not recognised (docs/motion.md)");
  cmd.add_option("--skeleton", o.skeleton, "H-Anim file (X3D or paper XML); default: the shipped 25-joint skeleton");
  cmd.add_option("--mesh", o.mesh,
                 "Skinned body to animate instead of the shipped one: a glTF 2.0 file (.glb/.gltf, plays its "
                 "animation), a MakeHuman hm08 folder (base.obj + default.mhskel + default_weights.mhw; walks), "
                 "or an X3D H-Anim file with a skin (plays its interpolators)");
  cmd.add_option("--clip", o.clip, "Clip to play: a name, an index, or 'all' (default: all clips together)");
  cmd.add_flag("--rest", o.rest, "Hold the rest pose instead of playing a clip");
  // Up to 2^53: every seed survives a round trip through summary.json in any JSON reader (doubles), and "-1" is
  // refused rather than wrapped to 2^64-1 as CLI11's unsigned conversion does.
  cmd.add_option("--seed", o.seed, "Seed for per-walker phase, rate and heading")->capture_default_str()
      ->check(whole_in(0, 9007199254740992.0, true));
  cmd.add_option("--spacing", o.spacing, "Metres between walkers on the grid (default: 1.25 scaled by the rig's stature over 1.75 m)")->capture_default_str()
      ->check(positive_up_to(1000))
      ->each([&o](const std::string&) { o.spacing_given = true; });
  cmd.add_option("--threads", o.threads, "Worker threads (0 = all cores; more than the cores run as many as the cores)")
      ->capture_default_str()->check(whole_in(0, 4096));
  // Parsed by DetailLevel::parse, the one place that knows level names; the validator runs first so a bad value
  // is a usage error naming the flag rather than an exception from the callback.
  const CLI::Validator body_level(
      [](std::string& value) -> std::string {
        if (DetailLevel::parse(value)) return {};
        return "must be 0, 1, 2, auto, impostor, S1, S2, S3 or -1, got '" + value + "'";
      },
      "0|1|2|auto|impostor|S1|S2|S3|-1");
  cmd.add_option_function<std::string>(
         "--level", [&o](const std::string& value) { o.level = *DetailLevel::parse(value); },
         "Body resolution level: 0 (17,953 vertices), 1 (8,923), 2 (5,133); auto: each walker by its height "
         "on screen (with hysteresis): levels 0-2, then impostors (walking crowds), the nearest --mesh-budget "
         "as meshes; impostor: every walker an impostor; S1, S2, S3: the 1,800-vertex cage skinned and "
         "Loop-subdivided 1-3 times every frame (7,194 / 28,770 / 115,074 vertices); -1 for skeletons only")
      ->check(body_level)->default_str(o.level.name());
  cmd.add_option("--mesh-budget", o.mesh_budget,
                 "Under --level auto, the most walkers drawn as meshes in a frame (the nearest); the rest of the "
                 "visible walkers are impostors. 0 = no cap")
      ->capture_default_str()->check(whole_in(0, 10000000));
  cmd.add_option("--impostor-px", o.impostor_px,
                 "Under --level auto, walkers shorter than this many pixels on screen are drawn as impostors "
                 "(0 = none)")
      ->capture_default_str()->check(finite_in(0, 100000));
  const CLI::Validator skinning_mode(
      [](std::string& value) -> std::string {
        if (parse_skinning_mode(value)) return {};
        return "must be lbs, dqs or cor, got '" + value + "'";
      },
      "lbs|dqs|cor");
  cmd.add_option_function<std::string>(
         "--skinning", [&o](const std::string& value) { o.skinning = *parse_skinning_mode(value); },
         "How joints are blended: lbs (linear blend, the paper's), dqs (dual quaternions: no collapse at bent "
         "or twisted joints), cor (optimised centres of rotation: no collapse, no bulge; precomputed once per "
         "body and cached)")
      ->check(skinning_mode)->default_str(skinning_mode_name(o.skinning));
  cmd.add_option("--muscles", o.muscles,
                 "Muscle layer: 'default' (the shipped 12 action lines, data/muscles.json), 'none', or a muscle "
                 "file (format: io/muscle_file.h)")->capture_default_str();
  cmd.add_option("--muscle-gain", o.muscle_gain, "Scale every muscle's forces (0 = no bulge, 1 = as in the file)")
      ->capture_default_str()->check(finite_in(0, 100));
  cmd.add_option("--muscle-overrides", o.muscle_overrides,
                 "JSON file of per-muscle gains, e.g. {\"gain\": 1, \"muscles\": {\"l_biceps\": 2}}");
  const CLI::Validator body_name(
      [](std::string& value) -> std::string {
        if (parse_shipped_body(value)) return {};
        return "must be makehuman or procedural, got '" + value + "'";
      },
      "makehuman|procedural");
  cmd.add_option_function<std::string>(
         "--body", [&o](const std::string& value) { o.body = *parse_shipped_body(value); },
         "Which shipped body the default skeleton wears: makehuman (derived from the MakeHuman hm08 base mesh, "
         "CC0) or procedural (grown from the skeleton); ignored with --mesh or an --skeleton that brings its skin")
      ->check(body_name)->default_str(shipped_body_name(o.body));
  cmd.add_option("--binding-overrides", o.binding_overrides,
                 "Skin binding overrides file (format: data/binding_overrides.json; e.g. saved by the binding "
                 "editor) used instead of the shipped one to bind the shipped body's levels and cage");
}

}  // namespace strata::cli
