#pragma once
// What `strata crowd` and `strata view` share: the options that describe the crowd scene, and building it.
#include <memory>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/skeleton_renderer.h"
#include "systems/frame_script.h"

namespace CLI {
class App;
}

namespace strata::cli {

struct SceneOptions {
  std::string motion;    // "walk" (walk generator along paths), "clip" (the file's interpolators); empty = walk
                         // when the skeleton has legs and arms to walk with, else clip; --clip implies clip
  std::size_t walkers = 25;
  std::string skeleton;  // empty = the embedded default skeleton
  std::string mesh;      // a skinned body to use instead: .glb/.gltf, a MakeHuman folder, or an X3D with a skin
  std::string clip;      // name, index or "all"; empty = all clips
  bool rest = false;
  std::uint64_t seed = 1;
  float spacing = 1.25f;
  int threads = 0;       // 0 = all cores
  int level = 0;         // body resolution level drawn (0 finest .. 2, subdiv_level(1..3) = S1..S3); -1 = no body
  std::string muscles = "default";  // "default" (data/muscles.json), "none", or a muscle file
  float muscle_gain = 1.0f;         // scales every muscle's forces
  std::string muscle_overrides;     // per-muscle gains file (io/muscle_file.h)
  std::string binding_overrides;    // step-3 overrides file replacing the shipped ones (shipped body only)
};

// Registers --walkers, --skeleton, --clip, --rest, --seed, --spacing, --threads, --level and the muscle options
// (--muscles, --muscle-gain, --muscle-overrides) and --binding-overrides on `cmd`.
void add_scene_options(CLI::App& cmd, SceneOptions& options);

// Resolves --clip to a walker clip selector: a clip name or index, "all" (every clip at once, as an X3D browser
// plays a scene's TimeSensors together; the default when the rig has clips), or kRestPose when `rest` is set
// or the rig has no clips. Throws std::invalid_argument naming the clip and listing the available ones.
int resolve_clip(const Rig& rig, const std::string& clip, bool rest);

// A rig from a skinned body file (see SceneOptions::mesh). Throws LoadError / std::invalid_argument.
Rig load_mesh_rig(const std::string& path);

// Loads the rig (LoadError on bad input), resolves the clip and spawns the grid.
std::unique_ptr<CrowdScene> build_scene(const SceneOptions& options);

// What the renderer needs to draw the scene's skinned bodies from the last simulate(): one input per body level
// in use (several under --level auto), empty when the scene has no body to draw.
std::vector<BodyDrawInput> body_draw_inputs(const CrowdScene& scene);
// Bounds of every skinned vertex drawn; false when none.
bool body_bounds(const CrowdScene& scene, glm::vec3& lo, glm::vec3& hi);
// The level-of-detail view (culling, projected sizes) of a camera rendering `viewport_height` pixels high.
LodView lod_view(const OrbitCamera& camera, float aspect, int viewport_height);

// Worker threads the options ask for, resolved against the machine.
int thread_count(const SceneOptions& options);

}  // namespace strata::cli
