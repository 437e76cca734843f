#pragma once
// Baking a rig's impostor atlas (components/impostor_atlas.h) through the engine's own frame: one walker of the
// rig walks a straight path in a private Crowd (the real locomotion, IK, FK, muscle and skin systems), and at each
// of the atlas's gait phases it is drawn from every atlas direction with an orthographic camera into the cells
// of that phase's layer (4x multisampled, then resolved, so edges carry fractional coverage).
//
// Cached on disk beside the body cache (rig/body_cache.h: $XDG_CACHE_HOME/strata, STRATA_NO_BODY_CACHE=1 turns it
// off), keyed by everything the images depend on: the rig's skeleton, the mesh level's rest positions, normals,
// triangles and binding, the muscle layer, the walk's style and speed, the layout, the skin colour and the bake
// code's version.
//
// What is baked is the walk generator's cycle at one speed (the crowd's mean lane speed) and the rig's own
// stature; walkers of other statures draw it scaled. Clip and motion-capture crowds have no impostors (their
// motion is not this walk, scene/body_settings.h crowd_may_use_impostors): they stay meshes.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>

#include <glm/vec3.hpp>

#include "components/impostor_atlas.h"
#include "components/rig.h"
#include "components/skin_layout.h"
#include "systems/locomotion.h"

namespace strata {

struct Crowd;

struct ImpostorBakeOptions {
  ImpostorAtlasLayout layout;
  // The body level drawn into the cells; clamped to the body's coarsest. Level 2 is what a walker is drawn with
  // just before it becomes an impostor (LodPolicy: below 160 px), so the switch changes the least; level 0 took
  // 3.5x longer to bake (32 s against 9 s here) for differences below a pixel at impostor sizes.
  int mesh_level = 2;
  float speed_m_s = 1.2f;   // the walk baked
  bool muscles = true;      // with the rig's muscle layer when it has one
  SkinningMode skinning = SkinningMode::Linear;  // the crowd's (scene/body_settings.h set_skinning_mode)
};

// The cache key of the atlas `options` would bake for `rig` walking with `style`.
std::uint64_t impostor_atlas_key(const Rig& rig, const GaitStyle& style, const ImpostorBakeOptions& options);

// Bakes the atlas. Needs a current GL 4.5 core context. Throws std::invalid_argument when the rig has no body or
// cannot walk, or the layout is invalid; std::runtime_error on a GL failure.
ImpostorAtlas bake_impostor_atlas(const Rig& rig, const GaitStyle& style, const ImpostorBakeOptions& options);

// The atlas from the cache in `cache_directory` when one matches, else baked (and stored there). nullopt
// directory: no cache. Needs a current GL context when it bakes.
ImpostorAtlas load_or_bake_impostor_atlas(const Rig& rig, const GaitStyle& style, const ImpostorBakeOptions& options,
                                          const std::optional<std::filesystem::path>& cache_directory);

// The atlas of `crowd`'s rig and walk (its mean lane speed, its skin colour), loaded or baked once and kept in
// crowd.impostor_atlas; nothing when the crowd cannot have impostors (scene/body_settings.h). Needs a current GL
// context the first time.
const ImpostorAtlas* ensure_impostor_atlas(Crowd& crowd);

}  // namespace strata
