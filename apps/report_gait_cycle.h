#pragma once
// The gait-cycle part of `strata report gait`: one walker's joint-angle curves over a normalised cycle
// (scene/gait_cycle.h) as JSON, checked against the normative ranges of issue 21 and the OpenSim subject
// (io/normative_gait.h), and drawn as an SVG side by side with the subject's curves.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/normative_gait.h"
#include "systems/gait_metrics.h"

namespace strata::cli {

// The targets a natural walk meets (normative gait, e.g. Winter's tables; docs/motion.md).
struct GaitCycleTargets {
  double rms_knee_hip_deg = 6.0, rms_ankle_deg = 5.0;
  double heel_strike_knee_max_deg = 8.0;
  double swing_peak_min_deg = 55.0, swing_peak_max_deg = 70.0;
  double stance_knee_min_max_deg = 10.0;
  double hip_min_deg = -25.0, hip_max_deg = 35.0;
  double excursion_min_cm = 2.5, excursion_max_cm = 5.0;
  double trunk_abs_max_deg = 6.0;
};

// {knee_flexion_deg: [101], ..., pelvis_vertical_excursion_cm, speed_m_s, cadence_steps_min, normative_rms_deg,
//  features, targets_met, ...}.
nlohmann::json gait_cycle_json(const GaitCycle& cycle, const NormativeGait& normative, bool curves,
                               const GaitCycleTargets& targets = {});

// An SVG (self-contained text) of the knee, hip, ankle, shoulder and trunk curves of `cycles` (the first drawn
// boldest) over the normative subject's knee, hip and ankle.
std::string gait_cycle_svg(const std::vector<GaitCycle>& cycles, const NormativeGait& normative);

}  // namespace strata::cli
