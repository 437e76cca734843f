#include "systems/gait_metrics.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/quaternion.hpp>

#include "components/euler.h"
#include "motion/gait.h"
#include "systems/ik.h"

namespace strata {
namespace {

glm::vec3 world_joint(const WalkerLanes& l, std::size_t w, std::int32_t joint) {
  const std::size_t s = l.stride;
  return placement_of(l, w).point({l.world[(joint * kAffineFloats + 9) * s + w], l.world[(joint * kAffineFloats + 10) * s + w],
                                   l.world[(joint * kAffineFloats + 11) * s + w]});
}

double distance_mm(const glm::vec3& a, const float ref[3]) {
  return 1000.0 * glm::length(a - glm::vec3(ref[0], ref[1], ref[2]));
}

}  // namespace

GaitMetrics::GaitMetrics(const Skeleton& skeleton, const LocomotionRig& rig, const GaitStyle& style)
    : skeleton_(skeleton), rig_(rig), style_(style) {
  report_.cadence_min = 1e9;
  report_.cadence_max = 0;
}

void GaitMetrics::observe(const WalkerLanes& l, const std::vector<CardinalSpline>& paths, float dt) {
  const std::size_t s = l.stride;
  if (walkers_.size() != l.count) walkers_.assign(l.count, WalkerTrack{});
  report_.walkers = l.count;
  ++report_.frames;
  report_.seconds += dt;
  const std::size_t joints = skeleton_.joint_count();

  for (std::size_t w = 0; w < l.count; ++w) {
    WalkerTrack& track = walkers_[w];
    // Non-finite values anywhere a system wrote.
    for (std::size_t c = 0; c < joints * 4; ++c) report_.nan_count += !std::isfinite(l.local_rotation[c * s + w]);
    for (std::size_t c = 0; c < joints * kAffineFloats; ++c) {
      report_.nan_count += !std::isfinite(l.world[c * s + w]);
      report_.nan_count += !std::isfinite(l.skinning[c * s + w]);
    }
    for (std::size_t c = 0; c < 5; ++c) report_.nan_count += !std::isfinite(l.placement[c * s + w]);

    // Joint limits of every limited joint, on the rotation the systems actually produced.
    for (std::size_t j = 0; j < joints; ++j) {
      const JointLimits& lim = skeleton_.limits[j];
      if (!lim.present) continue;
      const glm::quat q(l.local_rotation[(j * 4 + 3) * s + w], l.local_rotation[(j * 4 + 0) * s + w],
                        l.local_rotation[(j * 4 + 1) * s + w], l.local_rotation[(j * 4 + 2) * s + w]);
      const float v = limit_violation(lim, limit_angles(glm::mat3_cast(glm::normalize(q))));
      if (v > 1e-4f) ++report_.limit_violations;
      report_.limit_violation_max_rad = std::max<double>(report_.limit_violation_max_rad, v);
    }

    // IK outcome per limb, in world metres: the goal against where FK actually put the end joint (not the
    // solver's own error estimate), and the solver's flags.
    const float scale = l.placement[4 * s + w];
    for (std::uint32_t limb = 0; limb < kIkLimbs; ++limb) {
      const std::uint32_t flags = l.ik_flags[limb * s + w];
      const float* goal = l.ik_goal + static_cast<std::size_t>(limb) * kIkGoalFloats * s + w;
      if (l.ik_mode[limb * s + w] != static_cast<std::int32_t>(IkMode::Off)) {
        const std::int32_t end = rig_.limbs[limb].lower;
        const glm::vec3 reached{l.world[(end * kAffineFloats + 9) * s + w], l.world[(end * kAffineFloats + 10) * s + w],
                                l.world[(end * kAffineFloats + 11) * s + w]};
        const glm::vec3 wanted{goal[kGoalPx * s], goal[kGoalPy * s], goal[kGoalPz * s]};
        report_.ik_position_error_max_m =
            std::max<double>(report_.ik_position_error_max_m, glm::length(reached - wanted) * scale);
      }
      report_.ik_unreachable += (flags & kIkUnreachable) != 0;
      report_.ik_limits_infeasible += (flags & kIkLimitsInfeasible) != 0;
      report_.ik_orientation_clamped += (flags & kIkOrientationClamped) != 0;
    }

    const float cadence = l.gait[kGaitCadence * s + w];
    report_.cadence_min = std::min<double>(report_.cadence_min, cadence);
    report_.cadence_max = std::max<double>(report_.cadence_max, cadence);
    const float root_y = l.root_translation[1 * s + w] * scale;
    track.root_min = std::min(track.root_min, root_y);
    track.root_max = std::max(track.root_max, root_y);

    const float height = l.gait[kGaitHeight * s + w];
    const GaitParameters gp = gait_parameters(height, std::clamp(cadence, kMinCadence, kMaxCadence));
    const CardinalSpline& path = paths[l.path[w]];
    for (int leg = 0; leg < 2; ++leg) {
      LegTrack& t = track.legs[leg];
      const std::size_t base = kGaitLegs + static_cast<std::size_t>(leg) * kLegFloats;
      const bool swinging = l.gait[(base + kLegSwinging) * s + w] > 0.5f;
      const glm::vec3 ball = world_joint(l, w, rig_.ball[leg]);
      const glm::vec3 ankle = world_joint(l, w, rig_.limbs[leg == 0 ? kLeftLeg : kRightLeg].lower);
      t.cadence_sum += cadence;
      ++t.cadence_samples;
      if (!swinging && (t.swinging || first_)) {
        // Heel strike (or the first frame, already in stance): this footprint starts here.
        const float plant = l.gait[(base + kLegPlantDistance) * s + w];
        if (t.seen_strike && !first_) {
          float measured = plant - t.plant_distance;
          if (path.closed()) measured -= path.length() * std::floor(measured / path.length());
          const double mean_cadence = t.cadence_sum / std::max<std::uint32_t>(t.cadence_samples, 1);
          const double formula = 2.0 * 0.004 * mean_cadence * height;
          report_.stride_length_error_pct =
              std::max(report_.stride_length_error_pct, 100.0 * std::abs(measured - formula) / formula);
          stride_sum_ += measured;
          ++report_.strides;
        }
        t.seen_strike = !first_;
        t.plant_distance = l.gait[(base + kLegPlantDistance) * s + w];
        t.cadence_sum = 0;
        t.cadence_samples = 0;
        for (int k = 0; k < 3; ++k) {
          t.ball_ref[k] = ball[k];
          t.ankle_ref[k] = ankle[k];
        }
        t.ankle_tracking = true;
      }
      if (!swinging && !first_) {
        report_.foot_slide_ball_mm_max = std::max(report_.foot_slide_ball_mm_max, distance_mm(ball, t.ball_ref));
        // The ankle is planted until the heel rises.
        const float psi_frac = l.gait[kGaitPhase * s + w] - 0.5f * static_cast<float>(leg);
        const float psi = psi_frac - std::floor(psi_frac);
        if (t.ankle_tracking && psi / gp.stance_fraction() < style_.heel_off)
          report_.foot_slide_ankle_mm_max = std::max(report_.foot_slide_ankle_mm_max, distance_mm(ankle, t.ankle_ref));
        else
          t.ankle_tracking = false;
      }
      t.swinging = swinging;
    }
  }
  first_ = false;
}

GaitReport GaitMetrics::report() const {
  GaitReport r = report_;
  r.foot_slide_mm_max = std::max(r.foot_slide_ball_mm_max, r.foot_slide_ankle_mm_max);
  r.stride_length_mean_m = r.strides ? stride_sum_ / static_cast<double>(r.strides) : 0.0;
  double bob = 0;
  for (const WalkerTrack& t : walkers_) bob += 100.0 * (t.root_max - t.root_min);
  r.pelvis_bob_cm_mean = walkers_.empty() ? 0.0 : bob / static_cast<double>(walkers_.size());
  if (r.cadence_min > r.cadence_max) r.cadence_min = r.cadence_max = 0;
  return r;
}

}  // namespace strata
