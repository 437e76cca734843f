#include "apps/view_session.h"

#include <algorithm>

#include "profiling/profiler.h"

namespace strata::cli {

ViewSession::ViewSession(SceneOptions options) : options_(std::move(options)), scene_(build_scene(options_)) {
  panel_.walkers = static_cast<int>(std::min<std::size_t>(options_.walkers, 100000));
  panel_.seed = static_cast<int>(options_.seed);
}

bool ViewSession::apply_crowd_request() {
  if (!panel_.rebuild_requested) return false;
  panel_.rebuild_requested = false;
  SceneOptions next = options_;
  next.walkers = static_cast<std::size_t>(std::max(panel_.walkers, 1));
  next.seed = static_cast<std::uint64_t>(std::max(panel_.seed, 0));
  next.level = scene_->body_level();
  std::unique_ptr<CrowdScene> built = build_scene(next);
  // What the user tuned at run time survives a new crowd; the crowd itself (count, seed) is what changes.
  built->lod_policy() = scene_->lod_policy();
  built->style() = scene_->style();
  if (built->has_muscles()) {
    built->set_muscles_enabled(scene_->muscles_enabled());
    built->set_muscle_gains(scene_->muscle_gains());
  }
  scene_ = std::move(built);
  fresh_ = true;
  options_ = std::move(next);
  panel_.last_message = "new crowd: " + std::to_string(scene_->walker_count()) + " walkers, seed " +
                        std::to_string(options_.seed);
  return true;
}

float ViewSession::advance(float real_dt, Profiler& profiler) {
  if (!panel_.paused) {
    const float dt = std::max(real_dt, 0.0f) * std::clamp(panel_.time_scale, 0.0f, 10.0f);
    scene_->simulate(dt, profiler);
    fresh_ = false;
    return dt;
  }
  const int steps = std::max(panel_.step_requests, 0);
  panel_.step_requests = 0;
  constexpr float kStep = 1.0f / 30.0f;
  if (steps == 0 && fresh_) scene_->simulate(0.0f, profiler);
  fresh_ = false;
  for (int s = 0; s < steps; ++s) scene_->simulate(kStep, profiler);
  return static_cast<float>(steps) * kStep;
}

}  // namespace strata::cli
