#pragma once
// The state of one `strata view` session apart from its window: the scene, the panel's state, and what the
// panel's requests do (a new crowd that keeps the user's settings, pause / single-step / time scale). Kept out of
// cmd_view.cpp so the tests can drive it without a display.
#include <memory>

#include "apps/crowd_setup.h"
#include "ui/view_panel.h"

namespace strata {
class Profiler;
}

namespace strata::cli {

class ViewSession {
 public:
  // Builds the scene (LoadError / std::invalid_argument as build_scene).
  explicit ViewSession(SceneOptions options);

  CrowdScene& scene() { return *scene_; }
  ViewPanelState& panel() { return panel_; }
  const SceneOptions& options() const { return options_; }

  // Handles the panel's request for a new crowd: rebuilt with the panel's walker count and seed, keeping the body
  // level, level-of-detail policy, gait style, muscle switch and gains. True when the scene was replaced (the
  // caller reframes the camera; references into the old scene are gone).
  bool apply_crowd_request();

  // Advances the simulation for `real_dt` seconds of wall time: scaled by the panel's time scale while running;
  // while paused, one 1/30 s step per pending step request (and a 0 s frame when the scene is new, so a paused
  // new crowd still has bodies to draw). Returns the simulated seconds.
  float advance(float real_dt, Profiler& profiler);

 private:
  SceneOptions options_;
  std::unique_ptr<CrowdScene> scene_;
  ViewPanelState panel_;
  bool fresh_ = true;  // no simulate() since the scene was built
};

}  // namespace strata::cli
