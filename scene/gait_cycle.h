#pragma once
// One walker's gait cycle measured in isolation: a skeleton-only crowd of one walker of a given stature walks a
// straight path at a constant speed through the real frame script (locomotion -> IK -> FK), and a
// GaitCycleRecorder (systems/gait_metrics.h) averages its joint-angle curves over whole cycles. `strata report
// gait` and the gait tests read it; a crowd's walkers differ from it only in speed, stature and phase.
#include "components/rig.h"
#include "systems/gait_metrics.h"
#include "systems/locomotion.h"

namespace strata {

struct GaitCycleOptions {
  float speed = 1.2f;      // m/s, held constant (cadence from motion/gait.h cadence_for_speed)
  float height = 1.72f;    // stature, m (the crowds' mean)
  float fps = 60.0f;       // frame script steps per second
  int settle_cycles = 1;   // cycles walked before measuring
  int cycles = 3;          // whole cycles averaged
};

// Throws std::invalid_argument when the rig cannot walk or an option is not positive and finite.
GaitCycle measure_gait_cycle(const Rig& rig, const GaitStyle& style, const GaitCycleOptions& options = {});

}  // namespace strata
