#include "scene/gait_cycle.h"

#include <cmath>
#include <stdexcept>

#include "motion/gait.h"
#include "profiling/profiler.h"
#include "scene/body_settings.h"
#include "scene/crowd.h"
#include "scene/spawn.h"
#include "scene/step.h"

namespace strata {

GaitCycle measure_gait_cycle(const Rig& rig, const GaitStyle& style, const GaitCycleOptions& o) {
  if (!(o.speed > 0.0f) || !std::isfinite(o.speed) || !(o.height > 0.0f) || !std::isfinite(o.height) ||
      !(o.fps > 0.0f) || !std::isfinite(o.fps) || o.cycles < 1 || o.settle_cycles < 0)
    throw std::invalid_argument("measure_gait_cycle: speed, height and fps must be positive, cycles at least 1");
  // Joints only: the skin and muscle systems do not change a joint angle.
  Rig skeleton_only;
  skeleton_only.name = rig.name;
  skeleton_only.skeleton = rig.skeleton;
  Crowd scene(std::move(skeleton_only));
  if (!scene.motion.walk_error.empty()) throw std::invalid_argument(scene.motion.walk_error);
  scene.motion.style = style;
  scene.motion.source = MotionSource::Walk;
  // A straight open path long enough for the whole measurement: a curve would add the lane's turning to the
  // pelvis and feet, which a gait lab's straight walkway does not have.
  const GaitParameters gp = gait_parameters(o.height, cadence_for_speed(o.speed, o.height));
  const int total_cycles = o.settle_cycles + o.cycles + 2;
  const float length = gp.speed * gp.cycle_time * static_cast<float>(total_cycles) + 20.0f;
  set_paths(scene, {CardinalSpline({glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, length)}, 0.0f, false)});
  // Phase 0.5: the first left heel strike comes half a cycle in, after the start has settled.
  spawn_walker(scene, 0, 5.0f, 0.5f, o.height, gp.cadence, 0.0f, 0.0f, 0.0f);
  set_detail_level(scene, DetailLevel::none());

  GaitCycleRecorder recorder(scene.rig().skeleton, *scene.motion.locomotion, 0,
                             static_cast<std::size_t>(o.settle_cycles));
  Profiler profiler(1, false);
  const float dt = 1.0f / o.fps;
  const auto frames = static_cast<std::size_t>(std::ceil(gp.cycle_time * static_cast<float>(total_cycles) * o.fps));
  for (std::size_t f = 0; f < frames && recorder.cycles() < o.cycles; ++f) {
    step(scene, dt, profiler);
    recorder.observe(scene.lanes());
  }
  return recorder.cycle();
}

}  // namespace strata
