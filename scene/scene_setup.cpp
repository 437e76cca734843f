#include "scene/scene_setup.h"

#include "io/scenario_file.h"
#include "scene/crowd_agents.h"

#include <tbb/info.h>

#include <charconv>
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "io/bvh.h"
#include "io/hanim_loader.h"
#include "io/retarget_map_file.h"
#include "motion/bvh_naming.h"
#include "motion/retarget.h"
#include "io/gltf.h"
#include "io/makehuman.h"
#include "io/load_error.h"
#include "io/muscle_file.h"
#include "rig/binding.h"
#include "rig/body_generator.h"
#include "rig/body_rig.h"
#include "rig/muscle_binding.h"
#include "rig/skin_from_skeleton.h"
#include "scene/body_settings.h"
#include "scene/input_formats.h"
#include "scene/spawn.h"
#include "systems/animation_sample.h"

namespace strata {

namespace {

// The muscle layer --muscles asks for, bound to the rig's body.
void attach_muscles(Rig& rig, const SceneOptions& o, bool default_rig) {
  if (o.muscles == "none" || !rig.body) return;
  if (o.muscles == "default" && default_rig) {
    rig.muscles = default_muscle_rig(o.body);
    return;
  }
  try {
    MuscleSet set = o.muscles == "default" ? default_muscles(rig.skeleton) : load_muscle_file(o.muscles, rig.skeleton);
    rig.muscles = bind_muscle_rig(std::move(set), *rig.body);
  } catch (const LoadError& e) {
    // The shipped muscles name the shipped skeleton's joints; a foreign rig without them just has no muscles.
    if (o.muscles != "default") throw;
    std::fprintf(stderr, "note: no muscle layer for this rig (%s)\n", e.what());
  }
}

}  // namespace

int resolve_clip(const Rig& rig, const std::string& clip, bool rest) {
  if (rest || rig.clips.empty()) {
    if (!rest && !clip.empty() && clip != "all")
      throw std::invalid_argument("no clip '" + clip + "' in " + rig.skeleton.source + " (it has no animation)");
    return kRestPose;
  }
  if (clip.empty() || clip == "all") return kAllClips;
  for (std::size_t i = 0; i < rig.clips.size(); ++i)
    if (rig.clips[i].name == clip) return static_cast<int>(i);
  int index = -1;
  auto [end, ec] = std::from_chars(clip.data(), clip.data() + clip.size(), index);
  if (ec == std::errc() && end == clip.data() + clip.size() && index >= 0 &&
      static_cast<std::size_t>(index) < rig.clips.size())
    return index;
  std::string available;
  for (const AnimationClip& c : rig.clips) available += (available.empty() ? "" : ", ") + c.name;
  throw std::invalid_argument("no clip '" + clip + "' in " + rig.skeleton.source + " (available: " + available +
                              ", all)");
}

Rig load_mesh_rig(const std::string& path) {
  namespace fs = std::filesystem;
  const InputFormat& format = require_input(path, kGivesSkinnedBody, "--mesh");
  Rig rig;
  if (format.id == InputFormatId::Gltf || format.id == InputFormatId::MakeHuman) {
    ImportedBody imported = format.id == InputFormatId::Gltf ? load_gltf(path) : load_makehuman(path);
    rig.name = imported.mesh.name.empty() ? fs::path(path).stem().string() : imported.mesh.name;
    rig.skeleton = std::move(imported.skeleton);
    rig.clips = std::move(imported.clips);
    rig.body = std::make_shared<const Body>(Body{{BodyLevel{std::move(imported.mesh), std::move(imported.skin)}}});
  } else {
    rig = to_rig(load_humanoid_file(path));
    std::optional<BodyLevel> skin = skin_from_skeleton(rig.skeleton);
    if (!skin) throw std::invalid_argument(path + ": the file has no skin with weights (use --skeleton for bones)");
    rig.body = std::make_shared<const Body>(Body{{std::move(*skin)}});
  }
  return rig;
}

std::unique_ptr<Crowd> build_scene(const SceneOptions& o) {
  if (!o.binding_overrides.empty() && (!o.mesh.empty() || !o.skeleton.empty()))
    throw std::invalid_argument("--binding-overrides rebinds the shipped body; it cannot go with --mesh or --skeleton");
  Rig rig;
  if (!o.mesh.empty()) {
    rig = load_mesh_rig(o.mesh);
  } else {
    if (!o.skeleton.empty()) require_input(o.skeleton, kGivesSkeleton, "--skeleton");
    rig = to_rig(o.skeleton.empty() ? load_default_humanoid() : load_humanoid_file(o.skeleton));
    // The shipped skeleton comes with the shipped body; an X3D skeleton with a skin brings its own.
    // Loaded even without a body to draw, so a bad file fails the same way at every --level.
    const std::optional<BindingTables> tables =
        o.binding_overrides.empty()
            ? std::nullopt
            : std::optional(load_binding_overrides_file(o.binding_overrides, shipped_binding_tables(o.body)));
    if (!o.level.is_none()) {
      if (tables) {
        const BodyLevels& levels = shipped_body_levels(o.body);
        rig.body = bind_body(levels.levels, rig.skeleton, BindingMethod::ThreeStep, &levels.cage, &*tables);
      } else if (o.skeleton.empty()) {
        rig.body = default_bound_body(o.body);
      } else if (std::optional<BodyLevel> skin = skin_from_skeleton(rig.skeleton)) {
        rig.body = std::make_shared<const Body>(Body{{std::move(*skin)}});
      }
    }
  }
  attach_muscles(rig, o, o.mesh.empty() && o.skeleton.empty());
  CrowdConfig config;
  config.walkers = o.walkers;
  config.seed = o.seed;
  config.spacing = o.spacing;
  config.clip = resolve_clip(rig, o.clip, o.rest);
  auto scene = std::make_unique<Crowd>(std::move(rig));
  if (!o.retarget_map.empty() && !std::filesystem::path(o.motion).has_extension())
    throw std::invalid_argument("--retarget-map needs --motion FILE.bvh (it maps a capture's joints)");
  if (o.motion == "walk" || o.motion.empty()) {
    const bool implicit = o.motion.empty();
    if (implicit && (!o.clip.empty() || o.rest || !scene->motion.walk_error.empty())) {
      config.motion = MotionSource::Clip;
    } else {
      if (!scene->motion.walk_error.empty()) throw std::invalid_argument(scene->motion.walk_error);
      config.motion = MotionSource::Walk;
    }
  } else if (o.motion == "clip") {
    config.motion = MotionSource::Clip;
  } else if (std::filesystem::path(o.motion).has_extension()) {
    require_input(o.motion, kGivesMotion, "--motion");
    // Motion capture: its naming family recognised (motion/bvh_naming.h) and retargeted onto this skeleton, feet
    // locked by IK in stance.
    // A map file, when given, replaces the recognition (its rows' aims and the file's axes worked out the same way).
    const BvhMotion capture = load_bvh_file(o.motion);
    RetargetOptions retarget;
    if (!o.retarget_map.empty()) {
      const BvhNaming naming = bvh_naming_from_map(capture, load_retarget_map_file(o.retarget_map));
      retarget.map = naming.map;
      retarget.axes = naming.axes;
      retarget.family = naming.family;
    }
    set_mocap(*scene, retarget_bvh(capture, scene->rig().skeleton, retarget));
    config.motion = MotionSource::Mocap;
  } else {
    throw std::invalid_argument("--motion must be 'walk', 'clip' or a .bvh file, got '" + o.motion + "'");
  }
  if (config.motion == MotionSource::Clip) {
    // A grid of clip walkers plays each rig at its own size, so 1.25 m apart suits a person but not a 4 m giant or
    // a 30 cm doll: unless --spacing was given, the default scales with the rig's stature over 1.75 m (the body's
    // height, which the crowd measured for projected sizes, else the skeleton's). Walk and capture crowds are
    // scaled to people's heights and keep it.
    const float stature = scene->rig().body ? scene->skin.body_height : rest_stature(scene->rig().skeleton).metres;
    if (!o.spacing_given && stature > 0.0f && std::isfinite(stature))
      config.spacing = o.spacing * std::clamp(stature / 1.75f, 0.05f, 100.0f);
    // A rig that cannot walk and has nothing to play would stand still with no word why.
    if (scene->rig().clips.empty() && o.motion.empty() && !o.rest)
      std::fprintf(stderr, "note: %s has no clips and cannot walk (%s); showing its rest pose\n",
                   scene->rig().name.c_str(), scene->motion.walk_error.c_str());
  }
  // The skinning mode before the level, so the layouts are built once, with their centres; the level before the
  // walkers: under auto, walkers are spawned straight into the impostor table (scene/body_settings.h).
  set_skinning_mode(*scene, o.skinning);
  set_detail_level(*scene, o.level);
  if (!o.scenario.empty()) {
    if (config.motion != MotionSource::Walk)
      throw std::invalid_argument("--scenario: scenario agents walk; it cannot go with --motion clip, a capture, "
                                  "--clip or --rest");
    ScenarioSetup setup;
    setup.use_cache = o.navigation_cache;
    setup.agents = o.walkers_given ? o.walkers : 0;
    set_scenario(*scene, resolve_scenario(o.scenario), setup);
  } else {
    spawn_crowd(*scene, config);
  }
  if (o.level.is_mesh() && scene->rig().body && static_cast<std::size_t>(o.level.index()) >= scene->rig().body->levels.size())
    throw std::invalid_argument("--level " + o.level.name() + ": the body has " +
                                std::to_string(scene->rig().body->levels.size()) +
                                " level(s); use 0 to " + std::to_string(scene->rig().body->levels.size() - 1) +
                                ", auto or -1");
  if (o.level.is_impostor() && !crowd_may_use_impostors(*scene))
    throw std::invalid_argument("--level impostor: impostors show the walk generator's walk; this crowd " +
                                std::string(config.motion == MotionSource::Walk ? "has no body to bake them from"
                                                                                 : "plays a clip or a capture") +
                                " (use 0, 1, 2 or auto)");
  scene->lod.policy.mesh_budget = o.mesh_budget;
  scene->lod.policy.impostor_px = o.impostor_px;
  if (o.level.is_subdiv() && scene->skin.level != o.level)
    throw std::invalid_argument("--level " + o.level.name() +
                                " needs a subdivision cage; only the shipped body has one");
  if (scene->has_muscles()) {
    MuscleGains gains = o.muscle_overrides.empty() ? MuscleGains{}
                                                   : load_muscle_overrides(o.muscle_overrides, scene->rig().muscles->set);
    gains.global *= o.muscle_gain;
    set_muscle_gains(*scene, std::move(gains));
  }
  return scene;
}

// Capped at the cores TBB will use: global_control only limits parallelism, so asking for 1000 threads on two
// cores runs two, and summaries must report the two.
int thread_count(const SceneOptions& o) {
  const int cores = tbb::info::default_concurrency();
  return o.threads > 0 ? std::min(o.threads, cores) : cores;
}

}  // namespace strata
