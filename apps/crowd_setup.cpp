#include "apps/crowd_setup.h"

#include <CLI/CLI.hpp>
#include <tbb/info.h>

#include <charconv>
#include <stdexcept>

#include "io/bvh.h"
#include "io/hanim_loader.h"
#include "motion/retarget.h"
#include "rig/body_rig.h"
#include "systems/animation_sample.h"

namespace strata::cli {

void add_scene_options(CLI::App& cmd, SceneOptions& o) {
  cmd.add_option("--walkers,-n", o.walkers, "Number of walkers on the ground grid")->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, std::size_t{10'000'000}));
  cmd.add_option("--motion", o.motion,
                 "What moves the walkers: 'walk' (walk generator along a track; the default), 'clip' (the "
                 "file's own animation) or FILE.bvh (motion capture retargeted onto the skeleton, feet locked by IK)");
  cmd.add_option("--skeleton", o.skeleton, "H-Anim file (X3D or paper XML); default: the shipped 25-joint skeleton");
  cmd.add_option("--clip", o.clip, "Clip to play: a name, an index, or 'all' (default: all clips together)");
  cmd.add_flag("--rest", o.rest, "Hold the rest pose instead of playing a clip");
  cmd.add_option("--seed", o.seed, "Seed for per-walker phase, rate and heading")->capture_default_str();
  cmd.add_option("--spacing", o.spacing, "Metres between walkers on the grid")->capture_default_str();
  cmd.add_option("--threads", o.threads, "Worker threads (0 = all cores)")->capture_default_str();
  cmd.add_option("--level", o.level,
                 "Body resolution level: 0 (17,953 vertices), 1 (8,923), 2 (5,133), or -1 for skeletons only")
      ->capture_default_str()->check(CLI::Range(-1, 2));
}

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

std::unique_ptr<CrowdScene> build_scene(const SceneOptions& o) {
  Rig rig = to_rig(o.skeleton.empty() ? load_default_humanoid() : load_humanoid_file(o.skeleton));
  // The shipped skeleton comes with the shipped body; other skeletons are drawn as skeletons.
  if (o.skeleton.empty() && o.level >= 0) rig.body = default_bound_body(rig.skeleton);
  CrowdConfig config;
  config.walkers = o.walkers;
  config.seed = o.seed;
  config.spacing = o.spacing;
  config.clip = resolve_clip(rig, o.clip, o.rest);
  auto scene = std::make_unique<CrowdScene>(std::move(rig));
  if (o.motion == "walk" || o.motion.empty()) {
    const bool implicit = o.motion.empty();
    if (implicit && (!o.clip.empty() || o.rest || !scene->walk_unavailable().empty())) {
      config.motion = MotionSource::Clip;
    } else {
      if (!scene->walk_unavailable().empty()) throw std::invalid_argument(scene->walk_unavailable());
      config.motion = MotionSource::Walk;
    }
  } else if (o.motion == "clip") {
    config.motion = MotionSource::Clip;
  } else if (o.motion.size() > 4 && o.motion.compare(o.motion.size() - 4, 4, ".bvh") == 0) {
    // Motion capture: retargeted onto this skeleton by the Poser -> H-Anim map, feet locked by IK in stance.
    scene->set_mocap(retarget_bvh(load_bvh_file(o.motion), scene->rig().skeleton));
    config.motion = MotionSource::Mocap;
  } else {
    throw std::invalid_argument("--motion must be 'walk', 'clip' or a .bvh file, got '" + o.motion + "'");
  }
  scene->spawn_crowd(config);
  scene->set_body_level(o.level);
  return scene;
}

int thread_count(const SceneOptions& o) { return o.threads > 0 ? o.threads : tbb::info::default_concurrency(); }

}  // namespace strata::cli
