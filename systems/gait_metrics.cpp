#include "systems/gait_metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

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

// A point fixed to `joint` (its rest position `rest`) in world space, through the joint's FK frame.
glm::vec3 world_point(const WalkerLanes& l, std::size_t w, std::int32_t joint, const glm::vec3& rest,
                      const glm::vec3& rest_center) {
  const std::size_t s = l.stride;
  const float* m = l.world + static_cast<std::size_t>(joint) * kAffineFloats * s + w;
  const glm::vec3 d = rest - rest_center;
  glm::vec3 p;
  for (int r = 0; r < 3; ++r) p[r] = m[r * s] * d.x + m[(3 + r) * s] * d.y + m[(6 + r) * s] * d.z + m[(9 + r) * s];
  return placement_of(l, w).point(p);
}

double distance_mm(const glm::vec3& a, const float ref[3]) {
  return 1000.0 * glm::length(a - glm::vec3(ref[0], ref[1], ref[2]));
}

}  // namespace

double GaitMetrics::LegTrack::Contact::update(bool down, const glm::vec3& p) {
  if (!done && !tracking && down) {
    for (int k = 0; k < 3; ++k) ref[k] = p[k];
    tracking = true;
  } else if (tracking && !down) {
    tracking = false;
    done = true;
  }
  return tracking ? distance_mm(p, ref) : -1.0;
}

GaitMetrics::GaitMetrics(const Skeleton& skeleton, const LocomotionRig& rig, const GaitStyle& style)
    : skeleton_(skeleton), rig_(rig), style_(style) {
  report_.cadence_min = 1e9;
  report_.swing_clearance_min_mm = 1e9;
  report_.cadence_max = 0;
}

void GaitMetrics::observe(const WalkerLanes& l, const std::vector<CardinalSpline>& paths, float dt,
                          std::span<const std::uint32_t> walker_ids) {
  const std::size_t s = l.stride;
  const bool by_id = !walker_ids.empty();
  if (by_id && walker_ids.size() != l.count)
    throw std::invalid_argument("GaitMetrics::observe: " + std::to_string(walker_ids.size()) + " walker ids for " +
                                std::to_string(l.count) + " rows");
  if (!by_id && walkers_.size() != l.count) walkers_.assign(l.count, WalkerTrack{});
  report_.walkers = l.count;
  ++report_.frames;
  report_.seconds += dt;
  const std::size_t joints = skeleton_.joint_count();

  for (std::size_t w = 0; w < l.count; ++w) {
    const std::size_t id = by_id ? walker_ids[w] : w;
    if (id >= walkers_.size()) walkers_.resize(id + 1);
    WalkerTrack& track = walkers_[id];
    // A walker seen for the first time, or again after an absence, has no references to measure against yet.
    if (track.last_frame + 1 != report_.frames) track = WalkerTrack{};
    const bool fresh = track.last_frame == 0;  // this walker's first frame: no footprint to measure from
    track.last_frame = report_.frames;
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
    if (dt > 0.0f) {
      const glm::vec3 root = world_joint(l, w, 0);
      const glm::vec2 now(root.x, root.z);
      if (track.root_seen >= 1) {
        const glm::vec2 v = (now - track.root_xz[1]) / dt;
        report_.body_speed_max_mps = std::max<double>(report_.body_speed_max_mps, glm::length(v));
        if (track.root_seen >= 2) {
          const glm::vec2 before = (track.root_xz[1] - track.root_xz[0]) / dt;
          const double accel = glm::length(v - before) / dt;
          report_.body_accel_max_mps2 = std::max(report_.body_accel_max_mps2, accel);
          report_.body_jolts += accel > kBodyJoltAccel;
        }
      }
      track.root_xz[0] = track.root_xz[1];
      track.root_xz[1] = now;
      track.root_seen = std::min(track.root_seen + 1, 2);
    }

    const float height = l.gait[kGaitHeight * s + w];
    const GaitParameters gp = gait_parameters(height, std::clamp(cadence, kMinCadence, kMaxCadence));
    // Walkers following agents have no path: their plant distances are an odometer, never wrapped.
    const CardinalSpline* path = paths.empty() ? nullptr : &paths[std::min<std::size_t>(l.path[w], paths.size() - 1)];
    for (int leg = 0; leg < 2; ++leg) {
      LegTrack& t = track.legs[leg];
      const std::size_t base = kGaitLegs + static_cast<std::size_t>(leg) * kLegFloats;
      const bool swinging = l.gait[(base + kLegSwinging) * s + w] > 0.5f;
      const glm::vec3 ball = world_joint(l, w, rig_.ball[leg]);
      const std::int32_t ankle_joint = rig_.limbs[leg == 0 ? kLeftLeg : kRightLeg].lower;
      const glm::vec3 ankle = world_joint(l, w, ankle_joint);
      const glm::vec3 heel = world_point(l, w, ankle_joint, rig_.heel_rest[leg], skeleton_.centers[ankle_joint]);
      const glm::vec3 tip = world_point(l, w, rig_.ball[leg], rig_.tip_rest[leg], skeleton_.centers[rig_.ball[leg]]);
      t.cadence_sum += cadence;
      ++t.cadence_samples;
      if (!swinging && (t.swinging || fresh)) {
        // Heel strike (or the first frame, already in stance): this footprint starts here.
        const float plant = l.gait[(base + kLegPlantDistance) * s + w];
        if (t.seen_strike && !fresh) {
          float measured = plant - t.plant_distance;
          if (path && path->closed()) measured -= path->length() * std::floor(measured / path->length());
          const double mean_cadence = t.cadence_sum / std::max<std::uint32_t>(t.cadence_samples, 1);
          const double formula = 2.0 * 0.004 * mean_cadence * height;
          report_.stride_length_error_pct =
              std::max(report_.stride_length_error_pct, 100.0 * std::abs(measured - formula) / formula);
          stride_sum_ += measured;
          ++report_.strides;
        }
        t.seen_strike = !fresh;
        t.plant_distance = l.gait[(base + kLegPlantDistance) * s + w];
        t.cadence_sum = 0;
        t.cadence_samples = 0;
        for (int k = 0; k < 3; ++k) t.heel_ref[k] = heel[k];
        t.flat = false;
      }
      if (swinging) {
        // Ground clearance through the middle of the swing (20-80 %; it starts and ends on the ground): the lowest
        // of the toe tip and the heel above the ground (y = 0 here).
        const float psi_frac = l.gait[kGaitPhase * s + w] - 0.5f * static_cast<float>(leg);
        const float psi = psi_frac - std::floor(psi_frac);
        // An agent's early swing (locomotion.h GaitStyle::early_lift) progresses from where it left.
        const float early = l.gait[(base + kLegEarlyLift) * s + w];
        const float start = early >= 0.0f ? early : gp.stance_fraction();
        const float sigma = start < 1.0f ? (psi - start) / (1.0f - start) : 0.0f;
        if (sigma > 0.2f && sigma < 0.8f)
          report_.swing_clearance_min_mm = std::min(report_.swing_clearance_min_mm, 1000.0 * std::min(tip.y, heel.y));
      }
      if (!swinging && !fresh) {
        // Each contact point is still while it carries the foot: the heel through the heel rocker (heel strike to
        // foot flat), the ankle while the foot is flat, the ball until it lifts as the foot rolls onto the toe tip,
        // the toe tip to toe-off. References are taken where each phase starts. Flat and ball-down are read off
        // the pose itself (heel and ball within 0.1 mm of the ground), not off the heel rise's
        // schedule: the walk raises the heel as early as the body's progress needs (systems/locomotion.cpp
        // stance_pose), and a point that is still on the ground must not slide whatever the schedule says.
        const float psi_frac = l.gait[kGaitPhase * s + w] - 0.5f * static_cast<float>(leg);
        const float tau = (psi_frac - std::floor(psi_frac)) / gp.stance_fraction();
        if (tau < style_.heel_rocker) {
          report_.foot_slide_heel_mm_max = std::max(report_.foot_slide_heel_mm_max, distance_mm(heel, t.heel_ref));
        } else {
          // On the ground (y = 0 here): the heel's contact within 0.1 mm of it, the ball joint within 0.1 mm of
          // its rest height. A contact is tracked from the first frame it is down in this stance until it lifts.
          constexpr float kLifted = 1e-4f;  // m
          const bool heel_down = heel.y <= (rig_.heel_rest[leg].y) * scale + kLifted;
          const bool ball_down = ball.y <= skeleton_.centers[rig_.ball[leg]].y * scale + kLifted;
          if (!t.flat) {
            for (int k = 0; k < 3; ++k) t.tip_ref[k] = tip[k];
            t.flat = true;
            t.ankle.start(heel_down);
            t.ball.start(ball_down);
          }
          report_.foot_slide_ball_mm_max = std::max(report_.foot_slide_ball_mm_max, t.ball.update(ball_down, ball));
          report_.foot_slide_tip_mm_max = std::max(report_.foot_slide_tip_mm_max, distance_mm(tip, t.tip_ref));
          report_.foot_slide_ankle_mm_max =
              std::max(report_.foot_slide_ankle_mm_max, t.ankle.update(heel_down, ankle));
        }
      }
      t.swinging = swinging;
    }
  }
}

GaitReport GaitMetrics::report() const {
  GaitReport r = report_;
  r.foot_slide_mm_max = std::max({r.foot_slide_ball_mm_max, r.foot_slide_ankle_mm_max, r.foot_slide_heel_mm_max,
                                  r.foot_slide_tip_mm_max});
  r.stride_length_mean_m = r.strides ? stride_sum_ / static_cast<double>(r.strides) : 0.0;
  double bob = 0;
  std::size_t seen = 0;
  for (const WalkerTrack& t : walkers_)
    if (t.last_frame > 0) bob += 100.0 * (t.root_max - t.root_min), ++seen;
  r.pelvis_bob_cm_mean = seen == 0 ? 0.0 : bob / static_cast<double>(seen);
  if (r.cadence_min > r.cadence_max) r.cadence_min = r.cadence_max = 0;
  if (r.swing_clearance_min_mm > 1e8) r.swing_clearance_min_mm = 0;
  return r;
}

}  // namespace strata

// ---- GaitCycleRecorder --------------------------------------------------------------------------------------

namespace strata {
namespace {

// Signed angle (radians) that turns a's projection on the sagittal (YZ) plane into b's, about +X.
float sagittal_angle(const glm::vec3& a, const glm::vec3& b) {
  float d = std::atan2(b.z, b.y) - std::atan2(a.z, a.y);
  d -= 6.28318530718f * std::round(d / 6.28318530718f);
  return d;
}

constexpr float kDeg = 57.2957795131f;

}  // namespace

GaitCycleRecorder::GaitCycleRecorder(const Skeleton& skeleton, const LocomotionRig& rig, std::size_t walker,
                                     std::size_t skip_cycles)
    : walker_(walker), skip_(skip_cycles) {
  auto need = [&](const char* name) {
    const std::int32_t j = skeleton.find_joint(name);
    if (j < 0) throw std::invalid_argument(std::string("gait cycle: skeleton '") + skeleton.name + "' has no " + name);
    return j;
  };
  const LimbChain& leg = rig.limbs[kLeftLeg];
  const LimbChain& arm = rig.limbs[kLeftArm];
  rest_hip_ = rig.rest_hip_flexion;
  rest_knee_ = rig.rest_knee_flexion;
  rest_ankle_ = rig.rest_ankle_dorsiflexion;
  hip_ = leg.upper;
  knee_ = leg.middle;
  ankle_ = leg.lower;
  ball_ = rig.ball[0];
  shoulder_ = arm.upper;
  elbow_ = arm.middle;
  vl5_ = need("vl5");
  skullbase_ = need("skullbase");
  const auto& c = skeleton.centers;
  thigh_ = c[knee_] - c[hip_];
  shin_ = c[ankle_] - c[knee_];
  foot_ = c[ball_] - c[ankle_];
  upper_arm_ = c[elbow_] - c[shoulder_];
  trunk_ = c[skullbase_] - c[vl5_];
}

void GaitCycleRecorder::observe(const WalkerLanes& l) {
  if (walker_ >= l.count) return;
  const std::size_t s = l.stride, w = walker_;
  auto rotation = [&](std::int32_t j) {
    return glm::quat(l.local_rotation[(j * 4 + 3) * s + w], l.local_rotation[(j * 4 + 0) * s + w],
                     l.local_rotation[(j * 4 + 1) * s + w], l.local_rotation[(j * 4 + 2) * s + w]);
  };
  auto position = [&](std::int32_t j) {  // humanoid space: the walker's own frame, facing +Z
    return glm::vec3(l.world[(j * kAffineFloats + 9) * s + w], l.world[(j * kAffineFloats + 10) * s + w],
                     l.world[(j * kAffineFloats + 11) * s + w]);
  };
  Sample now;
  now.phase = l.gait[kGaitPhase * s + w];
  now.value[0] = kDeg * (rest_knee_ + sagittal_angle(shin_, rotation(knee_) * shin_));
  now.value[1] = kDeg * (rest_hip_ - sagittal_angle(thigh_, rotation(hip_) * thigh_));
  now.value[2] = kDeg * (rest_ankle_ - sagittal_angle(foot_, rotation(ankle_) * foot_));
  now.value[3] = -kDeg * sagittal_angle(upper_arm_, rotation(shoulder_) * upper_arm_);
  // Forward lean is the trunk's top moving to +Z: a positive turn about +X.
  now.value[4] = kDeg * sagittal_angle(trunk_, position(skullbase_) - position(vl5_));
  now.root_y = l.root_translation[1 * s + w] * l.placement[4 * s + w];
  const float cadence = l.gait[kGaitCadence * s + w];
  const float height = l.gait[kGaitHeight * s + w];

  const bool wrapped = started_ && now.phase < last_phase_ - 0.5f;
  if (wrapped && !current_.empty() && skip_ > 0) {
    --skip_;
  } else if (wrapped && !current_.empty()) {
    // A whole cycle from the last left heel strike to this one: the sample before it (phase - 1) and this one
    // (phase + 1) bracket it, so every one of the 101 points is interpolated, none extrapolated.
    std::vector<Sample> cycle;
    cycle.reserve(current_.size() + 2);
    if (current_.front().phase > 0.0f) {
      Sample before = last_before_cycle_;
      before.phase -= 1.0f;
      cycle.push_back(before);
    }
    cycle.insert(cycle.end(), current_.begin(), current_.end());
    Sample after = now;
    after.phase += 1.0f;
    cycle.push_back(after);
    std::size_t k = 0;
    for (int i = 0; i < kGaitCycleSamples; ++i) {
      const float x = static_cast<float>(i) / (kGaitCycleSamples - 1);
      while (k + 2 < cycle.size() && cycle[k + 1].phase < x) ++k;
      const Sample& a = cycle[k];
      const Sample& b = cycle[k + 1];
      const float u = b.phase > a.phase ? std::clamp((x - a.phase) / (b.phase - a.phase), 0.0f, 1.0f) : 0.0f;
      for (int c = 0; c < kCurves; ++c) sums_[c][i] += a.value[c] + u * (b.value[c] - a.value[c]);
    }
    float lo = 1e9f, hi = -1e9f;
    for (const Sample& x : current_) {
      lo = std::min(lo, x.root_y);
      hi = std::max(hi, x.root_y);
    }
    excursion_sum_ += 100.0 * (hi - lo);
    cadence_sum_ += cycle_cadence_ / std::max<std::size_t>(current_.size(), 1);
    height_sum_ += height;
    ++cycles_;
  }
  if (wrapped || !started_) {
    if (wrapped) last_before_cycle_ = last_;
    current_.clear();
    cycle_cadence_ = 0;
    // The first frame seen is mid-cycle; its samples only begin counting at the next heel strike.
    counting_ = wrapped;
  }
  if (counting_) {
    current_.push_back(now);
    cycle_cadence_ += cadence;
  }
  started_ = true;
  last_phase_ = now.phase;
  last_ = now;
}

GaitCycle GaitCycleRecorder::cycle() const {
  GaitCycle out;
  if (cycles_ == 0) return out;
  GaitCurve* curves[kCurves] = {&out.knee_flexion, &out.hip_flexion, &out.ankle_dorsiflexion, &out.shoulder_flexion,
                                &out.trunk_pitch};
  for (int c = 0; c < kCurves; ++c)
    for (int i = 0; i < kGaitCycleSamples; ++i) (*curves[c])[i] = static_cast<float>(sums_[c][i] / cycles_);
  out.cycles = cycles_;
  out.pelvis_vertical_excursion_cm = excursion_sum_ / cycles_;
  out.cadence_steps_min = cadence_sum_ / cycles_;
  out.height_m = height_sum_ / cycles_;
  out.speed_m_s = out.cadence_steps_min * out.cadence_steps_min * out.height_m / 15000.0;  // motion/gait.h
  return out;
}

GaitCycleFeatures gait_cycle_features(const GaitCycle& c) {
  GaitCycleFeatures f;
  if (c.cycles == 0 || !(c.height_m > 0.0)) return f;
  const float cadence = std::clamp(static_cast<float>(c.cadence_steps_min), kMinCadence, kMaxCadence);
  f.stance_fraction = gait_parameters(static_cast<float>(c.height_m), cadence).stance_fraction();
  const int toe_off = static_cast<int>(std::lround(100.0 * f.stance_fraction));
  f.heel_strike_knee_deg = c.knee_flexion[0];
  f.stance_knee_min_deg = 1e9;
  for (int i = 20; i <= toe_off; ++i) f.stance_knee_min_deg = std::min<double>(f.stance_knee_min_deg, c.knee_flexion[i]);
  for (int i = 0; i <= 25; ++i) f.loading_knee_peak_deg = std::max<double>(f.loading_knee_peak_deg, c.knee_flexion[i]);
  for (int i = toe_off; i < kGaitCycleSamples; ++i)
    f.swing_knee_peak_deg = std::max<double>(f.swing_knee_peak_deg, c.knee_flexion[i]);
  auto range = [](const GaitCurve& curve, double& lo, double& hi) {
    lo = *std::min_element(curve.begin(), curve.end());
    hi = *std::max_element(curve.begin(), curve.end());
  };
  range(c.hip_flexion, f.hip_min_deg, f.hip_max_deg);
  range(c.ankle_dorsiflexion, f.ankle_min_deg, f.ankle_max_deg);
  range(c.shoulder_flexion, f.shoulder_min_deg, f.shoulder_max_deg);
  range(c.trunk_pitch, f.trunk_min_deg, f.trunk_max_deg);
  return f;
}

NormativeRms normative_rms(const GaitCycle& cycle, const NormativeGait& normative) {
  return {curve_rms(cycle.knee_flexion, normative.knee_flexion), curve_rms(cycle.hip_flexion, normative.hip_flexion),
          curve_rms(cycle.ankle_dorsiflexion, normative.ankle_dorsiflexion)};
}

}  // namespace strata
