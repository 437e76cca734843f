#include "reference/skin_walk.h"

#include <algorithm>
#include <memory>
#include <stdexcept>

#include "reference/skin_metrics.h"
#include "scene/crowd.h"
#include "reference/skin_reference.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"

namespace strata {

WalkSkinMetrics measure_walk_skin(const Rig& rig_template, const BodyLevel& level, float seconds, float fps,
                                  SkinningMode mode, std::span<const glm::vec3> centres) {
  Rig rig = rig_template;
  auto body = std::make_shared<Body>();
  body->levels.push_back(level);
  rig.body = body;
  Crowd scene(rig);
  if (!scene.motion.walk_error.empty())
    throw std::invalid_argument("measure_walk_skin: " + scene.motion.walk_error);
  CrowdConfig config;
  config.walkers = 1;
  config.motion = MotionSource::Walk;
  spawn_crowd(scene, config);
  set_detail_level(scene, DetailLevel::none());  // skinned here in humanoid space, against the rest mesh
  Profiler profiler(8, false);
  WalkSkinMetrics out;
  const auto frames = static_cast<int>(seconds * fps);
  for (int f = 0; f < frames; ++f) {
    step(scene, 1.0f / fps, profiler);
    const std::vector<glm::mat4> skinning = walker_skinning_matrices(scene.lanes(), 0);
    const SkinnedVertices posed = skin_reference(level.mesh, level.binding, skinning, mode, centres);
    const SkinMetrics m = measure_skin(level.mesh, level.binding, skinning, posed.positions);
    if (m.inverted_triangles > out.inverted_triangles) {
      out.inverted_triangles = m.inverted_triangles;
      out.worst_frame = f;
    }
    out.seam_gap_max_m = std::max(out.seam_gap_max_m, m.seam_gap_max_m);
    out.nan_count += m.nan_count;
    ++out.frames;
  }
  return out;
}

}  // namespace strata
