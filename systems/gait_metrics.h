#pragma once
// Gait metrics: an observer run after FK that measures what a walking crowd really did — contact-point slide
// during stance, IK accuracy, joint-limit violations, non-finite values, stride length against the gait formula,
// pelvis bob. `strata report gait` and the locomotion tests read it.
#include <cstdint>
#include <vector>

#include "components/skeleton.h"
#include "components/walker.h"
#include "motion/cardinal_spline.h"
#include "systems/locomotion.h"

namespace strata {

struct GaitReport {
  std::size_t walkers = 0;
  std::size_t frames = 0;
  double seconds = 0;
  // Foot slide: the ball (midtarsal) over the whole stance and the ankle over its flat part, measured from the
  // FK output in world space, relative to where each was when its phase began; worst step, millimetres.
  double foot_slide_mm_max = 0, foot_slide_ball_mm_max = 0, foot_slide_ankle_mm_max = 0;
  double ik_position_error_max_m = 0;       // worst limb goal miss (FK end joint vs goal), world metres
  std::uint64_t ik_unreachable = 0, ik_limits_infeasible = 0, ik_orientation_clamped = 0;  // limb-frames flagged
  std::uint64_t limit_violations = 0;       // joint-frames whose local rotation leaves its limits by > 1e-4 rad
  double limit_violation_max_rad = 0;
  std::uint64_t nan_count = 0;              // non-finite values in rotations, matrices and placements
  std::uint64_t strides = 0;                // strides measured (consecutive heel strikes of one foot)
  double stride_length_error_pct = 0;       // worst |measured - formula| / formula, formula = 2 * 0.004 * f * H
  double stride_length_mean_m = 0;
  double pelvis_bob_cm_mean = 0;            // per walker peak-to-peak root height over the run, averaged
  double cadence_min = 0, cadence_max = 0;  // steps/min seen
};

class GaitMetrics {
 public:
  GaitMetrics(const Skeleton& skeleton, const LocomotionRig& rig, const GaitStyle& style);
  // Call once per frame after FK with the lanes the frame script just wrote.
  void observe(const WalkerLanes& lanes, const std::vector<CardinalSpline>& paths, float dt);
  GaitReport report() const;

 private:
  struct LegTrack {
    bool swinging = true;   // unknown until the first heel strike seen
    bool seen_strike = false;
    float plant_distance = 0;
    double cadence_sum = 0;
    std::uint32_t cadence_samples = 0;
    float ball_ref[3] = {0, 0, 0};
    float ankle_ref[3] = {0, 0, 0};
    bool ankle_tracking = false;
  };
  struct WalkerTrack {
    LegTrack legs[2];
    float root_min = 1e9f, root_max = -1e9f;
  };
  const Skeleton& skeleton_;
  const LocomotionRig& rig_;
  GaitStyle style_;
  std::vector<WalkerTrack> walkers_;
  GaitReport report_;
  double stride_sum_ = 0;
  bool first_ = true;
};

}  // namespace strata
