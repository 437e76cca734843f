#pragma once
// Gait metrics: an observer run after FK that measures what a walking crowd really did — contact-point slide
// during stance, IK accuracy, joint-limit violations, non-finite values, stride length against the gait formula,
// pelvis bob. `strata report gait` and the locomotion tests read it.
#include <cstdint>
#include <span>
#include <vector>

#include "components/skeleton.h"
#include "components/walker.h"
#include "io/normative_gait.h"
#include "motion/cardinal_spline.h"
#include "systems/locomotion.h"

namespace strata {

// A body's horizontal acceleration (m/s^2) past which GaitReport::body_jolts counts a frame: about 1 g, five times
// what a walk's own pelvis shows, a third of a metre a second gained or lost in one 30 fps frame.
inline constexpr double kBodyJoltAccel = 10.0;

struct GaitReport {
  std::size_t walkers = 0;
  std::size_t frames = 0;
  double seconds = 0;
  // Foot slide of each contact point while it carries the foot: the heel from heel strike to foot flat, the
  // ankle while the foot is flat, the ball (midtarsal) from foot flat until the toes bend no further, the toe tip
  // from foot flat to toe-off; measured from the FK output in world space, relative to where each was when its
  // phase began; worst step, millimetres. foot_slide_mm_max is the worst of them.
  double foot_slide_mm_max = 0, foot_slide_ball_mm_max = 0, foot_slide_ankle_mm_max = 0;
  double foot_slide_heel_mm_max = 0, foot_slide_tip_mm_max = 0;
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
  double swing_clearance_min_mm = 0;        // lowest toe tip or heel over the middle of any swing (20-80 %)
  // The body over the ground: the root joint's horizontal speed between two frames and its change between three
  // (world metres, seconds). A walk's pelvis moves at the walk's speed give or take its sway, and changes it by
  // 1-2 m/s^2; a body jerked to a foot it cannot otherwise reach, or stopped dead by one, changes it by far more
  // in a single frame, which no foot-slide figure shows. body_jolts counts walker-frames past kBodyJoltAccel.
  double body_speed_max_mps = 0;
  double body_accel_max_mps2 = 0;
  std::uint64_t body_jolts = 0;
};

class GaitMetrics {
 public:
  GaitMetrics(const Skeleton& skeleton, const LocomotionRig& rig, const GaitStyle& style);
  // Call once per frame after FK with the lanes the frame script just wrote. Tracks follow lane rows, or, given
  // `walker_ids` (one per row, e.g. entity indices), walkers: for a table whose rows change between frames
  // (walkers arriving from another process). A walker absent from the previous call starts afresh, as every
  // walker does on the first: its strides and contacts are measured from its next heel strike.
  void observe(const WalkerLanes& lanes, const std::vector<CardinalSpline>& paths, float dt,
               std::span<const std::uint32_t> walker_ids = {});
  GaitReport report() const;

 private:
  struct LegTrack {
    bool swinging = true;   // unknown until the first heel strike seen
    bool seen_strike = false;
    float plant_distance = 0;
    double cadence_sum = 0;
    std::uint32_t cadence_samples = 0;
    // A point that must stay put while its contact is on the ground: referenced the first frame it is down in a
    // stance, tracked until it lifts, not again until the next stance.
    struct Contact {
      float ref[3] = {0, 0, 0};
      bool tracking = false, done = false;
      void start(bool down) { tracking = false, done = !down; }  // a stance first seen lifted (starting mid-roll)
      // The distance (mm) from the reference while tracked, else a negative value.
      double update(bool down, const glm::vec3& p);
    };
    Contact ball, ankle;  // the ball while it is down; the ankle while the heel is down (the foot flat)
    float heel_ref[3] = {0, 0, 0};
    float tip_ref[3] = {0, 0, 0};
    bool flat = false;  // foot flat reached this stance (the toe tip's reference taken)
  };
  struct WalkerTrack {
    LegTrack legs[2];
    float root_min = 1e9f, root_max = -1e9f;
    // The root's last two horizontal positions (world), for the body's speed and acceleration; how many are held.
    glm::vec2 root_xz[2];
    int root_seen = 0;
    std::size_t last_frame = 0;  // report_.frames of the last call that saw it; 0: never seen
  };
  const Skeleton& skeleton_;
  const LocomotionRig& rig_;
  GaitStyle style_;
  std::vector<WalkerTrack> walkers_;
  GaitReport report_;
  double stride_sum_ = 0;
};

// One walker's joint-angle curves over a normalised gait cycle (0 = its left heel strike, the walk's phase 0),
// measured from the local rotations the systems wrote, as a gait lab reads a side view. Left side; degrees; the
// leg's angles in the lab's terms, zero for vertical thigh and shin over a flat foot (the rig's rest pose adds
// LocomotionRig::rest_*: the default leg leans 5 deg, and ISO 200x's centres bend the rest knee 18 deg):
//   knee_flexion         shin about the knee's hinge (+X) relative to the thigh, flexion positive
//   hip_flexion          thigh relative to the pelvis, thigh forward positive
//   ankle_dorsiflexion   hindfoot-to-midtarsal line relative to the shin, toes up positive
//   shoulder_flexion     upper arm relative to the shoulder's parent, arm forward positive
//   trunk_pitch          the vl5 -> skullbase line against its rest direction in the walker's own frame,
//                        forward lean positive
// Each is the sagittal (about +X) angle between a segment's rest direction and its rotated one, which is what a
// side-view goniometer measures; rejected: Euler angles of the joint rotation, whose X component mixes in the
// pelvic rotation and list at the hip.
struct GaitCycle {
  GaitCurve knee_flexion{}, hip_flexion{}, ankle_dorsiflexion{}, shoulder_flexion{}, trunk_pitch{};
  double pelvis_vertical_excursion_cm = 0;  // root height, peak to peak within a cycle, mean over the cycles
  double speed_m_s = 0, cadence_steps_min = 0, height_m = 0;
  int cycles = 0;                           // whole cycles averaged
};

class GaitCycleRecorder {
 public:
  // Throws std::invalid_argument when the skeleton lacks a joint the measures need.
  // The first `skip_cycles` whole cycles are seen but not counted (a walk settling after its start).
  GaitCycleRecorder(const Skeleton& skeleton, const LocomotionRig& rig, std::size_t walker = 0,
                    std::size_t skip_cycles = 0);
  // Call once per frame after FK. Samples between the walker's first and last observed left heel strikes count.
  void observe(const WalkerLanes& lanes);
  int cycles() const { return cycles_; }
  GaitCycle cycle() const;  // the mean of the whole cycles seen (all zero when none)

 private:
  static constexpr int kCurves = 5;
  struct Sample {
    float phase;
    float value[kCurves];
    float root_y;
  };
  std::size_t walker_, skip_;
  std::int32_t hip_, knee_, ankle_, ball_, shoulder_, elbow_, vl5_, skullbase_;
  glm::vec3 thigh_, shin_, foot_, upper_arm_, trunk_;
  float rest_hip_ = 0, rest_knee_ = 0, rest_ankle_ = 0;  // LocomotionRig::rest_* (rad)
  std::vector<Sample> current_;
  bool started_ = false;
  bool counting_ = false;
  float last_phase_ = 0;
  Sample last_{}, last_before_cycle_{};
  double cycle_cadence_ = 0;
  double sums_[kCurves][kGaitCycleSamples] = {};
  double excursion_sum_ = 0, cadence_sum_ = 0, height_sum_ = 0;
  int cycles_ = 0;
};

// The features a gait lab reads off the curves. Stance is the first stance_fraction of the cycle (motion/gait.h
// at the measured cadence and stature).
struct GaitCycleFeatures {
  double heel_strike_knee_deg = 0;    // knee flexion at 0 %
  double stance_knee_min_deg = 0;     // least knee flexion from 20 % to toe-off (terminal stance)
  double loading_knee_peak_deg = 0;   // most knee flexion in the first 25 % (loading response)
  double swing_knee_peak_deg = 0;     // most knee flexion in swing
  double hip_min_deg = 0, hip_max_deg = 0;
  double ankle_min_deg = 0, ankle_max_deg = 0;
  double shoulder_min_deg = 0, shoulder_max_deg = 0;
  double trunk_min_deg = 0, trunk_max_deg = 0;
  double stance_fraction = 0;
};
GaitCycleFeatures gait_cycle_features(const GaitCycle& cycle);

// Root mean square difference of a measured cycle and the normative subject (io/normative_gait.h), degrees.
struct NormativeRms {
  double knee = 0, hip = 0, ankle = 0;
};
NormativeRms normative_rms(const GaitCycle& cycle, const NormativeGait& normative);

}  // namespace strata
