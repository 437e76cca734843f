#pragma once
// Building a crowd scene from the options every scene command shares (crowd, view, bench, soak, the reports):
// which skeleton or mesh, which motion, how many walkers, which body level and muscle layer. The command line's
// flags for these options live in apps/scene_options.h; this file knows nothing of a command line.
#include <memory>
#include <string>
#include <vector>

#include "components/detail_level.h"
#include "rig/body_rig.h"
#include "scene/crowd.h"

namespace strata {

struct SceneOptions {
  std::string motion;    // "walk" (walk generator along paths), "clip" (the file's interpolators); empty = walk
                         // when the skeleton has legs and arms to walk with, else clip; --clip implies clip
  std::size_t walkers = 25;
  std::string skeleton;  // empty = the embedded default skeleton
  std::string mesh;      // a skinned body to use instead: .glb/.gltf, a MakeHuman folder, or an X3D with a skin
  std::string retarget_map;  // with a .bvh motion: a map file (io/retarget_map_file.h) instead of recognising names
  std::string clip;      // name, index or "all"; empty = all clips
  bool rest = false;
  std::uint64_t seed = 1;
  float spacing = 1.25f;  // grid spacing of clip walkers; scaled by the rig's stature / 1.75 m unless given
  bool spacing_given = false;
  int threads = 0;       // 0 = all cores
  DetailLevel level;     // body resolution drawn (components/detail_level.h); default mesh level 0
  SkinningMode skinning = SkinningMode::Linear;  // how joints are blended (components/skin_layout.h)
  std::string muscles = "default";  // "default" (data/muscles.json), "none", or a muscle file
  float muscle_gain = 1.0f;         // scales every muscle's forces
  std::string muscle_overrides;     // per-muscle gains file (io/muscle_file.h)
  std::string binding_overrides;    // step-3 overrides file replacing the shipped ones (shipped body only)
  ShippedBody body = kDefaultShippedBody;  // which shipped body the default skeleton wears (rig/body_rig.h)
  std::uint32_t mesh_budget = LodPolicy{}.mesh_budget;  // most walkers drawn as meshes under auto (0 = no cap)
  float impostor_px = LodPolicy{}.impostor_px;          // walkers shorter on screen are impostors under auto
  std::string scenario;  // a shipped scenario's name or a scenario file (components/scenario.h); empty = none
  bool walkers_given = false;  // --walkers was given: a scenario's groups are scaled to about `walkers` agents
  bool navigation_cache = true;  // scenarios: keep navigation meshes in the disk cache
};

// Resolves --clip to a walker clip selector: a clip name or index, "all" (every clip at once, as an X3D browser
// plays a scene's TimeSensors together; the default when the rig has clips), or kRestPose when `rest` is set
// or the rig has no clips. Throws std::invalid_argument naming the clip and listing the available ones.
int resolve_clip(const Rig& rig, const std::string& clip, bool rest);

// A rig from a skinned body file (see SceneOptions::mesh). Throws LoadError / std::invalid_argument.
Rig load_mesh_rig(const std::string& path);

// Loads the rig (LoadError on bad input), resolves the clip and spawns the grid.
std::unique_ptr<Crowd> build_scene(const SceneOptions& options);

// Worker threads the options ask for, resolved against the machine.
int thread_count(const SceneOptions& options);

}  // namespace strata
