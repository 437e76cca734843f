#include "systems/locomotion.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <utility>

#include <glm/gtc/quaternion.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "components/walker.h"
#include "motion/gait.h"
#include "systems/agent_move.h"
#include "systems/ik.h"

namespace strata {
namespace {

constexpr float kTwoPi = 6.28318530718f;
const glm::vec3 kUp{0.0f, 1.0f, 0.0f};

float frac(float x) { return x - std::floor(x); }

// 0 -> 0, 1 -> 1 with zero slope at both ends.
float smoothstep01(float x) {
  x = std::clamp(x, 0.0f, 1.0f);
  return x * x * (3.0f - 2.0f * x);
}

// A swing foot holds the pelvis down by its reach as it leaves the ground (before kSwingFreeFrom of its swing: the
// trailing leg's limit goes on smoothly past toe-off, which a cadence change moves) and as it comes in to land
// (from kSwingBindsFrom); in between the pelvis ignores it and the foot is drawn in to the leg's reach instead.
constexpr float kSwingFreeFrom = 0.2f;
constexpr float kSwingBindsFrom = 0.85f;

// Polynomial smooth minimum: never above min(a, b), equal to it when |a - b| >= k.
float smooth_min(float a, float b, float k) {
  const float h = std::max(k - std::abs(a - b), 0.0f) / k;
  return std::min(a, b) - h * h * k * 0.25f;
}

// Heading h faces (sin h, 0, cos h): +Z at 0, like H-Anim's forward.
float heading_of(const glm::vec3& tangent) { return std::atan2(tangent.x, tangent.z); }
glm::quat yaw(float h) { return glm::angleAxis(h, kUp); }
glm::quat pitch(float p) { return glm::angleAxis(p, glm::vec3(1.0f, 0.0f, 0.0f)); }

// Everything one walker's frame needs from its columns, gathered once so the maths below reads naturally.
struct Pose2 {
  glm::vec3 position;  // on the ground
  float heading;
};

Pose2 path_pose(const CardinalSpline& path, float distance) {
  return {path.point_at_length(distance), heading_of(path.tangent_at_length(distance))};
}


// Where the pelvis goes: along a path (the stadium lanes: the walker's own distance along a closed spline), or
// along a steered agent's trajectory (scenario crowds), predicted from its position, velocity and heading. The
// walk asks it for the pelvis now, at heel strikes to come (footprints) and at toe-offs past (restarts).
// Rejected: a per-agent spline through the recent trajectory and a predicted one; rebuilding an arc-length table
// per walker per frame cost more than the whole walk, and a footprint only needs the pose at one instant.
struct GroundTrack {
  const CardinalSpline* path = nullptr;  // path mode when set
  float distance = 0.0f;                 // path distance (path mode) or odometer (agents), now
  float speed = 0.0f;                    // m/s: the gait's along a path, the agent's |velocity|
  glm::vec2 position{0.0f};  // agents: ground (x, z); the body moves along its heading (systems/agent_move.h)
  glm::vec2 velocity{0.0f};  // agents: m/s
  float heading = 0.0f;      // agents: facing now
  float turn = 0.0f;         // agents: how far the body still turns to face its velocity (rad, signed)
  float course_turn = 0.0f;  // agents: how far its velocity still turns towards its steering target (rad, signed)
  float turn_rate = 0.0f;    // agents: rad/s
  float stop_distance = -1.0f;  // agents: metres it has left to brake to a stop; < 0 when it is not stopping
  float speed_ratio = 1.0f;  // agents: |velocity| over the gait's speed at its cadence, in [0, 1]

  // The pelvis `ahead` seconds from now (negative: in the past), `extra` metres further along its way.
  // Agents: along the agent's course, an arc turning towards its steering target at turn_rate (navigation's wish
  // turns no faster, systems/agent_move.h) and then a line, no further than its braking distance when it is
  // stopping; the body turning at turn_rate until it faces where it wants to go. The swing foot re-aims every
  // frame, so the prediction is never far from where the foot lands.
  Pose2 at(float ahead, float extra = 0.0f) const {
    if (path) return path_pose(*path, distance + speed * ahead + extra);
    const glm::vec2 along = speed > 1e-6f ? velocity / speed : glm::vec2(std::sin(heading), std::cos(heading));
    if (ahead <= 0.0f) {
      const glm::vec2 p = position + speed * ahead * along + extra * glm::vec2(std::sin(heading), std::cos(heading));
      return {{p.x, 0.0f, p.y}, heading};
    }
    float travel = speed * ahead;
    if (stop_distance >= 0.0f) travel = std::min(travel, stop_distance);
    // The direction of travel turns towards the steering target at turn_rate (navigation turns the wish that
    // way): an arc, then a straight line; the body faces along it.
    float hv = std::atan2(along.x, along.y);
    glm::vec2 p = position;
    const float turn_time = turn_rate > 0.0f ? std::abs(course_turn) / turn_rate : 0.0f;
    const float arc = speed > 1e-4f ? std::min(travel, speed * turn_time) : 0.0f;
    if (arc > 1e-5f && std::abs(course_turn) > 1e-4f) {
      const float w = course_turn > 0.0f ? turn_rate : -turn_rate;
      const float h1 = hv + w * (arc / speed);
      p += (speed / w) * glm::vec2(std::cos(hv) - std::cos(h1), std::sin(h1) - std::sin(hv));
      hv = h1;
    }
    p += (travel - arc) * glm::vec2(std::sin(hv), std::cos(hv));
    // The body's own heading catches up with its course at turn_rate.
    const float most = turn_rate * ahead;
    // Facing `turn` off its heading now: where it wants to go, which keeps its offset from the course (zero
    // unless avoidance pushes it aside) as the course turns.
    const float course_now = std::atan2(along.x, along.y);
    const float h = speed > 0.05f
                        ? heading + std::clamp(wrap_angle(hv + wrap_angle(heading + turn - course_now) - heading), -most, most)
                        : heading + std::clamp(turn, -most, most);
    p += extra * glm::vec2(std::sin(h), std::cos(h));
    return {{p.x, 0.0f, p.y}, h};
  }
  float distance_at(float ahead, float extra = 0.0f) const { return distance + speed * ahead + extra; }
};

// The flat footprint of leg `leg` under a pelvis at `p`: the rest ankle carried along.
Pose2 footprint(const LocomotionRig& rig, const Pose2& p, int leg, float scale) {
  return {p.position + yaw(p.heading) * (rig.ankle_rest[leg] * scale), p.heading};
}

// The footprint a swing lands on `strike_in` seconds from now. A turning agent's foot points where the body will
// face half-way through that stance, so the body turns over it from one side to the other (+-35 degrees at
// walking pace) rather than all one way (up to 80, past what hip, knee and ankle twist).
Pose2 landing_footprint(const LocomotionRig& rig, const GroundTrack& track, float strike_in, float lead, int leg,
                        float scale, float stance_time) {
  Pose2 p = track.at(strike_in, lead);
  if (!track.path) p.heading = track.at(strike_in + 0.5f * stance_time, lead).heading;
  return footprint(rig, p, leg, scale);
}

// The foot's pitch in the heel rise by schedule, from heel_off to toe-off (fraction of stance tau): a cubic from
// rest to toe_off_pitch, still rising at toe-off at heel_rise_end_slope times its mean rate. The least the heel
// rises: stance_pose raises it sooner where the body's progress needs it (GaitStyle::heel_hold_from).
float heel_rise_pitch(float tau, const GaitStyle& style) {
  const float x = std::clamp((tau - style.heel_off) / (1.0f - style.heel_off), 0.0f, 1.0f);
  return style.toe_off_pitch * (x * x * (3.0f - 2.0f * x) + style.heel_rise_end_slope * x * x * (x - 1.0f));
}

struct AnklePose {
  glm::vec3 position;
  glm::quat orientation;  // the foot's frame in world axes
};

// How much of a leg's straight reach the pelvis may use. A straight leg's length changes by only 1 - cos(b/2) as
// its knee bends by b, so the fraction is a knee angle: 0.998 held the knee at 7.5 deg at the longest, 0.9999 at
// 1.6 (the subject's terminal-stance knee is 4-5 deg, its heel-strike knee -2).
constexpr float kReachUsed = 0.9999f;

// The hip-ankle distance (humanoid units) the normative stance knee gives at tau, the fraction of stance done.
float stance_target_reach(const LocomotionRig& rig, int leg, float tau) {
  const float x = std::clamp(tau, 0.0f, 1.0f) * static_cast<float>(kStanceKnots - 1);
  const std::size_t k = std::min(static_cast<std::size_t>(x), kStanceKnots - 2);
  const float u = x - static_cast<float>(k);
  return glm::mix(rig.stance_reach[leg][k], rig.stance_reach[leg][k + 1], u);
}

// The foot rolled heel-up by `p` (rad, >= 0) on its footprint: about the ball (midtarsal) and, past the toes'
// limit, about the toe tip; each pivot's ground contact stays put.
AnklePose rolled_pose(const LocomotionRig& rig, int leg, const glm::vec3& plant, const glm::quat& h, float p,
                      float scale) {
  glm::vec3 ball = plant + h * ((rig.ball_rest[leg] - rig.ankle_rest[leg]) * scale);
  const float over = p - rig.toe_limit;
  if (over > 0.0f) {
    // The toes bend no further: the forefoot pitches about its tip, which stays put, and lifts the ball. This
    // second rocker is what lets the trailing leg reach its foot at toe-off with the pelvis only ~3-4 cm below
    // mid-stance; rolling about the ball alone needed a 7 cm dip (and a crouch) at every double support.
    const glm::vec3 tip = plant + h * ((rig.tip_rest[leg] - rig.ankle_rest[leg]) * scale);
    ball = tip + (h * pitch(over)) * ((rig.ball_rest[leg] - rig.tip_rest[leg]) * scale);
  }
  const glm::quat q = h * pitch(p);
  return {ball + q * ((rig.ankle_rest[leg] - rig.ball_rest[leg]) * scale), q};
}

// How much of the ankle's inversion / eversion a stance leg leaning sideways may use (walk_one's body hold).
constexpr float kRollUsed = 0.85f;

// How far short of the ankle's plantarflexion limit the heel hold stops rolling the foot (rad).
constexpr float kAnkleLimitMargin = 0.02f;

// Where the stance leg's hip is or will be (world) and how far from it the ankle may be (world units): the heel
// rises no later than this distance needs.
struct HipHold {
  glm::vec3 hip;
  float reach;
};

// Stance: toes up at heel strike rolling down about the heel (tau < heel_rocker, pitch strike_pitch at tau 0),
// flat on the footprint until the heel rises, then rolling about the ball (midtarsal) and, past the toes' limit,
// about the toe tip; each pivot's ground contact stays put. tau is the fraction of stance done.
// With `hold`, the heel rises as soon as, and as fast as, the body moving on over the foot needs it to keep the
// ankle within hold->reach of the hip, and never later than heel_rise_pitch's schedule: as a person's heel comes
// up when the leg is straight and the body goes on (Perry's third rocker), and with this walker's step and
// speed. A schedule alone rose early for a slow step and late for a fast one, and the pelvis sank 3-5 cm
// in terminal stance waiting for it (issue 21: the other leg's late-swing knee then 15-20 deg bent).
AnklePose stance_pose(const LocomotionRig& rig, int leg, const glm::vec3& plant, float plant_heading, float tau,
                      float scale, const GaitStyle& style, float* foot_pitch, float strike_pitch = 0.0f,
                      const HipHold* hold = nullptr) {
  const glm::quat h = yaw(plant_heading);
  if (tau < style.heel_rocker) {
    // Heel rocker: toes up at heel strike, rolling down about the heel's ground contact to foot flat. The toes
    // follow the foot (no midtarsal bend), so the reported pitch is 0.
    const float p = -strike_pitch * (1.0f - smoothstep01(tau / style.heel_rocker));
    if (foot_pitch) *foot_pitch = 0.0f;
    const glm::vec3 heel = plant + h * ((rig.heel_rest[leg] - rig.ankle_rest[leg]) * scale);
    const glm::quat q = h * pitch(p);
    return {heel + q * ((rig.ankle_rest[leg] - rig.heel_rest[leg]) * scale), q};
  }
  float p = heel_rise_pitch(tau, style);
  AnklePose pose = rolled_pose(rig, leg, plant, h, p, scale);
  const bool hip_ahead = hold && glm::dot(hold->hip - pose.position, h * glm::vec3(0.0f, 0.0f, 1.0f)) > 0.0f;
  if (hip_ahead && tau >= style.heel_hold_from && glm::length(pose.position - hold->hip) > hold->reach) {
    // Rolling lifts the ankle on a circle about the pivot (the ball, then, past the toes' limit, the toe tip:
    // the ball then turns about the tip with the foot, so the ankle does too): the least pitch that brings it
    // within reach is where that circle enters the sphere about the hip, in closed form. Up to 1.3 rad
    // (74 deg): a foot that would need more is left there, and the pelvis' own reach limit lowers it instead.
    // Rejected: bisection on the pitch (3.5x the system's time at 14 steps).
    const glm::quat to_foot = glm::conjugate(h);
    auto first_within = [&](const glm::vec3& pivot, const glm::vec3& v, float lo) {
      // |R_x(q) v - H|^2 <= D^2  <=>  B cos q + C sin q >= E, with H the hip about the pivot in the foot's axes.
      const glm::vec3 hip = to_foot * (hold->hip - pivot);
      const float b = hip.y * v.y + hip.z * v.z, c = hip.z * v.y - hip.y * v.z;
      const float e = 0.5f * (glm::dot(v, v) + glm::dot(hip, hip) - hold->reach * hold->reach) - hip.x * v.x;
      if (b * std::cos(lo) + c * std::sin(lo) >= e) return lo;
      const float r = std::hypot(b, c);
      if (e > r) return 1e9f;
      const float start = std::atan2(c, b) - std::acos(std::clamp(e / r, -1.0f, 1.0f));
      return start + kTwoPi * std::ceil((lo - start) / kTwoPi);
    };
    const glm::vec3 ankle_from_ball = (rig.ankle_rest[leg] - rig.ball_rest[leg]) * scale;
    float q = 1e9f;
    if (p < rig.toe_limit) {
      q = first_within(plant + h * ((rig.ball_rest[leg] - rig.ankle_rest[leg]) * scale), ankle_from_ball, p);
      if (q > rig.toe_limit) q = 1e9f;
    }
    if (q > 1e8f) {
      const glm::vec3 ankle_from_tip =
          pitch(-rig.toe_limit) * ((rig.ball_rest[leg] - rig.tip_rest[leg]) * scale) + ankle_from_ball;
      q = first_within(plant + h * ((rig.tip_rest[leg] - rig.ankle_rest[leg]) * scale), ankle_from_tip,
                       std::max(p, rig.toe_limit));
    }
    p = std::min(q, 1.3f);
    pose = rolled_pose(rig, leg, plant, h, p, scale);
  }
  if (hold) {
    // No further than the ankle plantarflexes: past its limit IK keeps the shin and turns the foot about the ankle
    // and the toe lifts off the ground, as it did for agents whose body had moved on (the plaza's largest slide
    // 81 -> 63 mm with this, measured with an earlier form of the body's lag), and for agents pushed back over a
    // foot planted ahead, whose shin leans back while the schedule raises the heel (issue 16: the crossing's
    // toe tips 5-11 cm up at 80 % of stance, the ankle 0.2-0.5 m in front of the hip). The shin leans forward of
    // the ankle-hip line by the knee's bend at this distance. Below the schedule too: the least pitch the
    // schedule asks is for a body going on over its foot. A free walk never comes near it (0 orientation clamps
    // over the gait report, which this leaves unchanged).
    const glm::quat to_foot = glm::conjugate(h);
    const glm::vec3 to_hip = to_foot * (hold->hip - pose.position);
    const float d = std::min(glm::length(to_hip), rig.leg_reach[leg] * scale);
    const float a = rig.thigh_length[leg] * scale, b = rig.shin_length[leg] * scale;
    const float bend = std::acos(std::clamp((b * b + d * d - a * a) / (2.0f * b * std::max(d, 1e-6f)), -1.0f, 1.0f));
    const float most = std::atan2(to_hip.z, to_hip.y) + bend - rig.rest_ankle_dorsiflexion +
                       rig.ankle_plantarflexion_limit - kAnkleLimitMargin;
    if (p > most) {
      p = std::max(most, 0.0f);
      pose = rolled_pose(rig, leg, plant, h, p, scale);
    }
  }
  if (foot_pitch) *foot_pitch = p;
  return pose;
}

struct WalkerFrame {
  glm::vec3 position;  // placement on the ground
  float heading;
  float scale;
  glm::vec3 to_humanoid(const glm::vec3& world) const {
    return (yaw(-heading) * (world - position)) / scale;
  }
  glm::quat to_humanoid(const glm::quat& world) const { return yaw(-heading) * world; }
};

// Accessor for one walker's gait columns.
struct GaitRef {
  float* base;
  std::size_t stride, i;
  float& operator[](std::uint32_t c) const { return base[c * stride + i]; }
  float& leg(int l, std::uint32_t c) const { return base[(kGaitLegs + l * kLegFloats + c) * stride + i]; }
};

// The step length (m at rig scale) the walk's step-dependent shapes are set for: the strike pitch, the lead's
// fraction and the arm swing scale with a step against it.
constexpr float kReferenceStep = 0.7f;

// This frame's step (an agent's shortened by its speed ratio) in reference steps.
float reference_steps(const GaitParameters& gp, const GroundTrack& track, float scale) {
  return gp.step_length * track.speed_ratio / (kReferenceStep * scale);
}

// How far a step runs beyond 1.05 kReferenceStep, in reference steps: 0 for the default walker (1.02 at 1.2 m/s)
// and anyone slower, 0.17-0.24 at 1.8 m/s. The fast walk's own shapes (GaitStyle::*_long_step_*) grow with it, so
// the walk the joint search fitted at 1.2 m/s stays as it was.
float long_step_excess(const GaitParameters& gp, const GroundTrack& track, float scale) {
  return std::max(reference_steps(gp, track, scale) - 1.05f, 0.0f);
}

// How far ahead of the pelvis at heel strike a footprint lands: the lead of a whole step, shortened in proportion
// when an agent moves slower than its cadence's speed (a stopping walker's last step lands beside the other foot).
// The fraction of the step varies with the step's length against kReferenceStep (GaitStyle::lead_long_step_drop,
// lead_short_step_rise).
float footprint_lead(const GroundTrack& track, const GaitParameters& gp, const GaitStyle& style, float scale) {
  const float ratio = gp.step_length / (kReferenceStep * scale);
  const float fraction = style.footprint_lead - style.lead_long_step_drop * std::max(ratio - 1.0f, 0.0f) +
                         style.lead_short_step_rise * std::max(1.0f - ratio, 0.0f);
  float along = 1.0f;
  if (!track.path && track.speed > 0.05f) {
    // Agents carried backwards (avoidance pushing them back in a jam) step back: the lead shrinks with the
    // velocity's backward share c (1 + back_step_lead c, c < 0), to nothing at 42 deg behind sideways and to half
    // a lead behind the pelvis when moving straight back. Led forwards regardless, feet landed ahead of a
    // receding body and were left out of reach (the plaza's largest slides: hip 0.34-0.50 m behind the planted
    // ankle). Largest foot slide crossing / plaza / bottleneck 88 / 169 / 81 -> 76 / 103 / 71 mm; 1, 2, 2.5 and 4
    // measured 103 / 103, 83 / 133, 121 / 191 and 164 / 191 (crossing / plaza), and the lead along the velocity
    // for sideways motion too (it shrinks a sidestep's lead) 107 / 191.
    const float c = glm::dot(track.velocity / track.speed, glm::vec2(std::sin(track.heading), std::cos(track.heading)));
    if (c < 0.0f) along = std::clamp(1.0f + style.back_step_lead * c, -1.0f, 1.0f);
  }
  return along * fraction * gp.step_length * track.speed_ratio;
}

// A leg's planted footprint and the swing it starts at toe-off, written where walk_one and start_walking need them.
void plant_foot(const GaitRef& g, int leg, const glm::vec3& position, float heading, float distance) {
  g.leg(leg, kLegPlantX) = position.x;
  g.leg(leg, kLegPlantY) = position.y;
  g.leg(leg, kLegPlantZ) = position.z;
  g.leg(leg, kLegPlantHeading) = heading;
  g.leg(leg, kLegPlantDistance) = distance;
  g.leg(leg, kLegSwinging) = 0.0f;
}

// `early_lift`: the leg phase the swing leaves at when that is before toe-off (locomotion.h GaitStyle::early_lift);
// negative for a swing leaving at toe-off, whose progress follows the stance fraction as the cadence changes.
void begin_swing(const GaitRef& g, int leg, const glm::vec3& from, float from_heading, float from_pitch,
                 const glm::vec3& to, float to_heading, float to_distance, float early_lift = -1.0f) {
  g.leg(leg, kLegEarlyLift) = early_lift;
  g.leg(leg, kLegFromX) = from.x;
  g.leg(leg, kLegFromY) = from.y;
  g.leg(leg, kLegFromZ) = from.z;
  g.leg(leg, kLegFromHeading) = from_heading;
  g.leg(leg, kLegFromPitch) = from_pitch;
  g.leg(leg, kLegToX) = to.x;
  g.leg(leg, kLegToY) = to.y;
  g.leg(leg, kLegToZ) = to.z;
  g.leg(leg, kLegToHeading) = to_heading;
  g.leg(leg, kLegToDistance) = to_distance;
  g.leg(leg, kLegSwinging) = 1.0f;
}

void write_quat(const LocomotionColumns& lanes, std::int32_t joint, std::size_t i, const glm::quat& q) {
  if (joint < 0) return;
  const auto j = static_cast<std::uint32_t>(joint);
  lanes.local_rotation.at(j * 4 + 0, i) = q.x;
  lanes.local_rotation.at(j * 4 + 1, i) = q.y;
  lanes.local_rotation.at(j * 4 + 2, i) = q.z;
  lanes.local_rotation.at(j * 4 + 3, i) = q.w;
}

void write_goal(const LocomotionColumns& lanes, std::uint32_t limb, std::size_t i, const glm::vec3& position,
                const glm::quat& orientation, IkMode mode) {
  const std::size_t s = lanes.ik_goal.stride;
  float* g = lanes.ik_goal.component(limb * kIkGoalFloats) + i;
  g[kGoalPx * s] = position.x;
  g[kGoalPy * s] = position.y;
  g[kGoalPz * s] = position.z;
  g[kGoalQx * s] = orientation.x;
  g[kGoalQy * s] = orientation.y;
  g[kGoalQz * s] = orientation.z;
  g[kGoalQw * s] = orientation.w;
  lanes.ik_mode.at(limb, i) = static_cast<std::int32_t>(mode);
  g[kGoalSwivel * s] = 0.0f;
  g[kGoalPoleX * s] = g[kGoalPoleY * s] = g[kGoalPoleZ * s] = 0.0f;  // the rig's pole
}

// Pelvis rotation (yaw, list, constant anterior tilt) and sideways shift at a gait phase.
struct PelvisMotion {
  glm::quat sacro;
  float sway;
  float yaw;
};

// `walking` scales the walk's rotation and sway (0 for a standing agent) and `extra_sway` adds the stance's slow
// weight shift.
PelvisMotion pelvis_motion(const GaitStyle& style, float phase, float walking = 1.0f, float extra_sway = 0.0f) {
  const float angle = kTwoPi * phase;
  PelvisMotion m;
  m.yaw = -walking * style.pelvis_yaw * std::cos(angle);             // left hip forward at left heel strike
  // Right side down in left stance, lagging by pelvis_list_lag of a cycle (the subject's list is still large at the
  // next heel strike).
  const float tilt = walking * style.pelvis_tilt * std::sin(angle - kTwoPi * style.pelvis_list_lag);
  m.sacro = yaw(m.yaw) * glm::angleAxis(tilt, glm::vec3(0.0f, 0.0f, 1.0f)) * pitch(style.pelvis_anterior_tilt);
  m.sway = walking * style.lateral_sway * std::sin(angle) + extra_sway;
  return m;
}

// A hip's position (humanoid units) for root translation (sway, 0, 0): rt + c_sacro + R_sacro (c_hip - c_sacro).
glm::vec3 hip_position(const LocomotionRig& rig, const PelvisMotion& motion, int leg) {
  return glm::vec3(motion.sway, 0.0f, 0.0f) + rig.sacro_center + motion.sacro * (rig.hip_rest[leg] - rig.sacro_center);
}

// The same hip with the pelvis at root translation `root` (whose x is the sway).
glm::vec3 hip_at_root(const LocomotionRig& rig, const PelvisMotion& motion, const glm::vec3& root, int leg) {
  return root + (hip_position(rig, motion, leg) - glm::vec3(motion.sway, 0.0f, 0.0f));
}

// How far (humanoid units, along the ground) the hip at `hip` is beyond what leg `leg` reaches of its ankle at
// `ankle` (both humanoid, the foot turned `foot_yaw` from the body): past the leg's length with the pelvis lag_dip
// below standing, and across the foot past the ankle's roll (the shin leans over the foot's long axis, the ankle
// inverting or everting as far as it leans: at most ankle_roll_limit, 20 degrees for H-Anim's default, past which
// IK clamps the foot and its edge or toe tip leaves the ground; measured from the rest stance's offset). Moving
// the hip by minus this, or the ankle by it, brings them within reach; zero when they are. The hold (walk_one)
// moves the body so, a landing foot (GaitStyle::land_within_reach) moves its footprint.
glm::vec3 beyond_reach(const LocomotionRig& rig, const GaitStyle& style, int leg, const glm::vec3& hip,
                       const glm::vec3& ankle, float foot_yaw, float scale) {
  const float reach = kReachUsed * rig.leg_reach[leg];
  const float below = hip.y - style.lag_dip / scale - ankle.y;  // hip above the ankle at the lowest pelvis
  if (below <= 0.0f || below >= reach) return glm::vec3(0.0f);
  const float allowed = std::sqrt(reach * reach - below * below);
  glm::vec2 apart(hip.x - ankle.x, hip.z - ankle.z);
  glm::vec3 beyond(0.0f);
  const float d = glm::length(apart);
  if (d > allowed) {
    beyond += glm::vec3(apart.x, 0.0f, apart.y) * ((d - allowed) / d);
    apart *= allowed / d;
  }
  const glm::vec2 across(std::cos(foot_yaw), -std::sin(foot_yaw));  // the foot's +X in the body's frame
  const float rest_across = rig.hip_rest[leg].x - rig.ankle_rest[leg].x;
  const float lateral = glm::dot(apart, across) - rest_across;
  const float lateral_room = below * std::tan(kRollUsed * rig.ankle_roll_limit);
  if (std::abs(lateral) > lateral_room)
    beyond += glm::vec3(across.x, 0.0f, across.y) * (lateral - std::copysign(lateral_room, lateral));
  return beyond;
}

// A stance heel's hold (stance_pose) for the hip at `hip` (humanoid units) of a walker placed at `placement`:
// the hip in world units and the hip-ankle distance the normative stance knee gives at tau.
HipHold hip_hold_at(const LocomotionRig& rig, const Pose2& placement, const glm::vec3& hip, int leg, float tau,
                    float scale) {
  return {placement.position + yaw(placement.heading) * (hip * scale), stance_target_reach(rig, leg, tau) * scale};
}

// The highest root translation y (humanoid units) at which both hips still reach their ankles (world positions),
// for a pelvis placed by `frame` and moving as `motion`. smooth > 0 blends the two legs' limits (continuous
// output for the per-frame value); 0 takes the plain minimum.
// A leg whose `binds` is false (a swing foot far from landing) is left out.
float reach_limit(const LocomotionRig& rig, const WalkerFrame& frame, const PelvisMotion& motion,
                  const glm::vec3 ankle_world[2], float start, float smooth, const bool binds[2],
                  const float* leg_reach = nullptr) {
  float dy = start;
  for (int leg = 0; leg < 2; ++leg) {
    if (!binds[leg]) continue;
    const glm::vec3 a = frame.to_humanoid(ankle_world[leg]);
    const glm::vec3 hip = hip_position(rig, motion, leg);
    const float reach = leg_reach ? leg_reach[leg] : kReachUsed * rig.leg_reach[leg];
    const float dx = hip.x - a.x, dz = hip.z - a.z;
    const float limit = a.y + std::sqrt(std::max(reach * reach - dx * dx - dz * dz, 0.0f)) - hip.y;
    dy = smooth > 0.0f ? smooth_min(dy, limit, smooth) : std::min(dy, limit);
  }
  return dy;
}

// Gait parameters at the walker's current cadence, tolerant of a cadence column outside the fitted range.
GaitParameters current_gait(const GaitRef& g) {
  return gait_parameters(g[kGaitHeight], std::clamp(g[kGaitCadence], kMinCadence, kMaxCadence));
}

// The speed schedule's target cadence at clock time `time`, when the walker has a schedule.
void schedule_cadence(const GaitRef& g, float time, const GaitStyle& style) {
  if (g[kGaitBaseSpeed] > 0.0f) {
    const float speed = g[kGaitBaseSpeed] *
                        (1.0f + g[kGaitSpeedAmplitude] * std::sin(kTwoPi * time / style.speed_period + g[kGaitSpeedPhase]));
    g[kGaitCadenceTarget] = cadence_for_speed(speed, g[kGaitHeight]);
  }
}

// The gait clock of walker i: time, cadence, phase and path distance advanced by dt, and its placement on the
// path. Everything an impostor needs, and all the state a walk keeps besides its footprints; the walk (walk_one)
// and the far walkers' job (GaitAdvanceJob) both run exactly this, so a walker changing tier is at the same
// place and phase whichever job moved it.
struct GaitClock {
  GaitParameters gp;
  GroundTrack track;
  Pose2 pelvis;
  float scale;
};

// An index past the scene's paths follows the last one (a caller that shrank the path list keeps walking).
const CardinalSpline& path_of(std::span<const CardinalSpline> paths, std::uint32_t index) {
  return paths[std::min<std::size_t>(index, paths.size() - 1)];
}

// Where the walker's pelvis goes: its path, or (agent views set) its agent's trajectory.
struct TrackSource {
  std::span<const CardinalSpline> paths;
  ColumnView<const std::uint32_t> path;
  ColumnView<const float> agent;  // empty: path mode
  bool agents() const { return agent.components > 0; }
};

// Agents: the walk's cadence for an agent moving at `speed`. The gait formula's, but never below a stepping pace:
// a walker turning on the spot or easing to a stop steps at a natural rate with short steps, where the formula's
// cadence at a crawl (40 steps/min) looked like slow motion.
float agent_cadence(float speed, float height, const GaitStyle& style) {
  return std::clamp(std::max(cadence_for_speed(speed, height), style.agent_min_cadence), kMinCadence, kMaxCadence);
}

// The pelvis now on `track`, written to the walker's placement: the clock's result whichever track it follows.
GaitClock finish_clock(const GaitParameters& gp, const GroundTrack& track, ColumnView<float> placement, std::size_t i,
                       float scale) {
  const Pose2 pelvis = track.at(0.0f);
  placement.at(0, i) = pelvis.position.x;
  placement.at(1, i) = 0.0f;
  placement.at(2, i) = pelvis.position.z;
  placement.at(3, i) = pelvis.heading;
  placement.at(4, i) = scale;
  return {gp, track, pelvis, scale};
}

GaitClock advance_gait_clock(const LocomotionRig& rig, const TrackSource& source, const GaitRef& g, float& time,
                             ColumnView<float> placement, std::size_t i, float dt, const GaitStyle& style,
                             float hurry = 1.0f) {
  time += dt;
  const float scale = g[kGaitHeight] / rig.rig_height;
  GroundTrack track;
  if (source.agents()) {
    // The agent moved the body (systems/agent_move.h); the gait keeps time with it. Its velocity is already
    // limited in acceleration and turning, so the cadence follows it directly rather than easing; a walker
    // standing (kGaitIdle > 0) holds its phase.
    const ColumnView<const float>& a = source.agent;
    // The body follows the agent, off it by the lag a planted foot imposed (walk_one). The lag eases out
    // (lag_release), no faster than lag_catch_up, and the body's velocity carries that catch-up so its footprints
    // are planned for where it really goes. Measured, largest foot slide crossing / plaza / bottleneck: 88 / 169
    // / 81 mm. Rejected: eased out exponentially alone (a 0.3 m lag asks for an extra metre a second): 128 / 192 /
    // 119; with the rate limit but the catch-up left out of the velocity: 82 / 139 / 88, one crossing agent
    // never arriving.
    glm::vec2 lag(g[kGaitLagX], g[kGaitLagZ]), catch_up(0.0f);
    const float lag_length = glm::length(lag);
    if (lag_length > 0.0f && dt > 0.0f) {
      const float reduce =
          std::min(lag_length * (1.0f - std::exp(-dt / style.lag_release)), style.lag_catch_up * scale * dt);
      catch_up = -lag * (reduce / (lag_length * dt));
      lag *= 1.0f - reduce / lag_length;
      g[kGaitLagX] = lag.x;
      g[kGaitLagZ] = lag.y;
    }
    track.position = glm::vec2(a.at(kAgentPx, i), a.at(kAgentPz, i)) + lag;
    track.heading = a.at(kAgentHeading, i);
    // The body moves with its velocity and turns to face where it wants to go (agent_move.h).
    const glm::vec2 agent_v(a.at(kAgentVx, i), a.at(kAgentVz, i)), wish(a.at(kAgentPrefVx, i), a.at(kAgentPrefVz, i));
    const glm::vec2 target(a.at(kAgentTargetX, i), a.at(kAgentTargetZ, i));
    track.velocity = agent_v + catch_up;
    track.speed = glm::length(track.velocity);
    track.turn_rate = turn_rate_at(track.speed, style.turn_rate, style.turn_in_place_rate);
    const glm::vec2 face = facing_direction(agent_v, wish, target - glm::vec2(a.at(kAgentPx, i), a.at(kAgentPz, i)),
                                            style.face_velocity_speed, style.face_side_angle, style.face_side_speed);
    if (face.x != 0.0f || face.y != 0.0f) track.turn = wrap_angle(std::atan2(face.x, face.y) - track.heading);
    const glm::vec2 to_target = target - track.position;
    // The course turns towards the steering target only while the agent goes where it wishes (navigation turns
    // the wish that way). Carried off its wish by avoidance, it is predicted straight on: predicted turning back
    // to a target avoidance kept it from, footprints landed on a curve the body never took, beside and ahead of
    // it (a walker carried across its wish at 1.1 m/s: 11 mm of slide, 0.08 mm predicted straight on).
    const float wish_speed = glm::length(wish);
    const bool steering = glm::length(agent_v - wish) <= style.steering_tolerance * std::max(wish_speed, style.stand_speed);
    if (steering && track.speed > 0.05f && glm::length(to_target) > 0.3f)
      track.course_turn = wrap_angle(std::atan2(to_target.x, to_target.y) - std::atan2(track.velocity.x, track.velocity.y));
    if (wish_speed < style.stand_speed) track.stop_distance = track.speed * track.speed / (2.0f * style.agent_braking);
    g[kGaitCadenceTarget] = g[kGaitCadence] = agent_cadence(track.speed, g[kGaitHeight], style);
    const GaitParameters gp = current_gait(g);
    if (g[kGaitIdle] <= 0.0f) g[kGaitPhase] = frac(g[kGaitPhase] + hurry * dt / gp.cycle_time);
    g[kGaitDistance] += track.speed * dt;
    track.distance = g[kGaitDistance];
    track.speed_ratio = std::clamp(track.speed / gp.speed, 0.0f, 1.0f);
    return finish_clock(gp, track, placement, i, scale);
  }
  const CardinalSpline& path = path_of(source.paths, source.path.at(0, i));
  // Speed schedule -> cadence target -> eased cadence. Phase and distance integrate it: no pop on change.
  schedule_cadence(g, time, style);
  const float max_step = style.cadence_rate * dt;
  g[kGaitCadence] += std::clamp(g[kGaitCadenceTarget] - g[kGaitCadence], -max_step, max_step);
  const GaitParameters gp = current_gait(g);
  g[kGaitPhase] = frac(g[kGaitPhase] + dt / gp.cycle_time);
  g[kGaitDistance] += gp.speed * dt;
  if (path.closed() && g[kGaitDistance] >= path.length()) {
    // Keep the distance small so float precision holds over hours; footprint distances are compared modulo
    // the path length.
    g[kGaitDistance] -= path.length();
  }
  track.path = &path;
  track.distance = g[kGaitDistance];
  track.speed = gp.speed;
  return finish_clock(gp, track, placement, i, scale);
}

// Agents: whether the walker wants to stand, from its velocity and the velocity it would like.
bool agent_wants_to_stand(const ColumnView<const float>& agent, std::size_t i, const GaitStyle& style) {
  const float v = std::hypot(agent.at(kAgentVx, i), agent.at(kAgentVz, i));
  const float pref = std::hypot(agent.at(kAgentPrefVx, i), agent.at(kAgentPrefVz, i));
  return v < style.stand_speed && pref < style.stand_speed;
}

// Whether IK could not bring leg `leg` of walker i to its goal in the last frame (the body pushed away from it).
bool unreachable(const LocomotionColumns& lanes, int leg, std::size_t i) {
  return (lanes.ik_flags.at(static_cast<std::uint32_t>(leg), i) & (kIkUnreachable | kIkLimitsInfeasible)) != 0u;
}

// Whether IK will hold leg `leg`'s ankle on the goal locomotion just wrote for walker i (its goal slot, mode and
// the local rotations and root translation written this frame): the IK system's own steps (ik.h joint_frame,
// limb_solve_input, solve_limb) run ahead of it, so the answer is the system's flags bit for bit.
bool stance_foot_holds(const LocomotionRig& rig, const LocomotionColumns& lanes, std::size_t i, int leg) {
  const auto limb_index = static_cast<std::uint32_t>(leg == 0 ? kLeftLeg : kRightLeg);
  const LimbChain& limb = rig.limbs[limb_index];
  // The hip's parent frame, composed from the root down (hip_ancestors is that chain, root first).
  JointFrame parent;
  if (rig.hip_ancestors[leg].empty())
    parent.g = glm::dvec3(lanes.root_translation.at(0, i), lanes.root_translation.at(1, i),
                          lanes.root_translation.at(2, i));
  for (const std::int32_t joint : rig.hip_ancestors[leg])
    parent = joint_frame(rig.skeleton, joint, parent, lanes.local_rotation, lanes.root_translation, i);
  LimbSolveInput in;
  if (limb_solve_input(limb, limb_index, parent, lanes.ik_goal, lanes.ik_mode, i, in) != LimbRequest::Solve)
    return true;  // nothing IK will pull on
  return (solve_limb(rig.skeleton, limb, in).flags & (kIkUnreachable | kIkLimitsInfeasible)) == 0u;
}

// Whether a stance leg at leg phase psi (stance fraction sf) that its leg cannot reach lifts early
// (GaitStyle::early_lift): past that fraction of its stance, and after the other foot is down (psi 0.5; with a
// margin, which the heel-strike test, psi < 0.5, also needs).
bool lifts_early(float psi, float sf, const GaitStyle& style) {
  return style.early_lift > 0.0f && psi < sf && psi >= std::max(style.early_lift * sf, 0.505f);
}

void walk_one(const LocomotionRig& rig, const TrackSource& source, const LocomotionColumns& lanes, std::size_t i,
              float dt, const GaitStyle& base_style) {
  GaitRef g{lanes.gait.base, lanes.gait.stride, i};
  // Agents: a stance leg IK could not bring to its planted foot last frame ends its stance sooner (stance_hurry),
  // unless it lifts early this frame anyway (its stance fraction read before the clock moves, which may shift it
  // slightly): hurried as well, the lifting foot moved 7.5 cm in its first frame at 60 fps.
  float hurry = 1.0f;
  if (source.agents() && lanes.ik_flags.components != 0) {
    const float sf_before = current_gait(g).stance_fraction();
    // Whether leg l, in stance, lifts early this frame (nor is it hurried when the other leg's does).
    auto stance_lifts_early = [&](int l) {
      return g.leg(l, kLegSwinging) < 0.5f &&
             lifts_early(frac(g[kGaitPhase] - 0.5f * static_cast<float>(l)), sf_before, base_style);
    };
    for (int leg = 0; leg < 2; ++leg)
      if (g.leg(leg, kLegSwinging) < 0.5f && unreachable(lanes, leg, i) && !stance_lifts_early(leg) &&
          !stance_lifts_early(1 - leg))
        hurry = base_style.stance_hurry;
  }
  const GaitClock clock =
      advance_gait_clock(rig, source, g, lanes.time.at(0, i), lanes.placement, i, dt, base_style, hurry);
  // An agent stepping slower than its cadence's speed rolls off its toes less: a full 63-degree toe-off under a
  // body that hardly moves forward asks the ankle for more plantarflexion than it has, and IK's clamp then pivots
  // the foot on the ground (measured: 5 cm of toe-tip slide while stopping).
  GaitStyle walk_style = base_style;
  if (source.agents() && clock.track.speed_ratio < 1.0f)
    walk_style.toe_off_pitch *= std::max(clock.track.speed_ratio, 0.3f);
  walk_style.heel_rise_end_slope *= smoothstep01((clock.gp.cadence - 90.0f) / 20.0f);
  // A long fast step turns the pelvis and lists it further and rolls the trailing foot further onto its toes, as
  // people's do (docs/motion.md, the fast walk); the same step's swing lifts the foot less (lift_long_step_drop).
  const float longer = long_step_excess(clock.gp, clock.track, clock.scale);
  walk_style.pelvis_yaw += base_style.yaw_long_step_rise * longer;
  walk_style.pelvis_tilt += base_style.tilt_long_step_rise * longer;
  walk_style.toe_off_pitch += base_style.toe_off_long_step_rise * longer;
  walk_style.bob_curvature *= std::max(1.0f - base_style.bob_long_step_drop * longer, 0.3f);
  const GaitStyle& style = walk_style;
  const GaitParameters& gp = clock.gp;
  GroundTrack track = clock.track;  // agents: moved with the pelvis below
  const float phase = g[kGaitPhase];
  const float scale = clock.scale;
  Pose2 pelvis = clock.pelvis;  // agents: moved back below if a planted foot holds the body (lag_dip)
  WalkerFrame frame{pelvis.position, pelvis.heading, scale};
  const float lead = footprint_lead(track, gp, style, scale);

  // The pelvis' placement `ahead` seconds from now. Within the look-ahead window it is interpolated between now
  // and the window's end: over the ~0.4 m it covers a lane's curvature moves it by under a millimetre, and one
  // path evaluation instead of one per sample cut the system from 7 to ~4 us per walker.
  const float window = 0.28f;  // of a cycle: short enough that a leg changes mode at most once
  const float window_time = window * gp.cycle_time;
  Pose2 window_end = track.at(window_time);
  float heading_change = window_end.heading - pelvis.heading;
  heading_change -= kTwoPi * std::round(heading_change / kTwoPi);
  auto pelvis_ahead = [&](float ahead) -> Pose2 {
    if (ahead <= 0.0f) return pelvis;
    if (ahead > window_time) return track.at(ahead);
    const float u = ahead / window_time;
    return {glm::mix(pelvis.position, window_end.position, u), pelvis.heading + u * heading_change};
  };
  const float sf = gp.stance_fraction();
  const float step_ratio = std::clamp(reference_steps(gp, track, scale), 0.5f, 1.0f);
  const float strike_pitch = style.heel_strike_pitch * step_ratio * step_ratio;
  // Each leg's ankle pose now and a little ahead. Ahead, a leg may change mode once: a stance leg lifts off
  // into the swing it will take (predicted exactly as the toe-off event will place it, at today's cadence), a
  // swinging leg lands on its target. Arcs are built once per frame.
  // The swing ankle: a Cardinal spline in time through knots placed by the normative swing's joint angles on
  // this walker's legs (kSwingHipDeg...). Along the step each knot sits where the ankle is, relative to a hip
  // moving on at walking pace, as a fraction of the way from toe-off to heel strike; upwards, at the height the
  // leg's angles lift it above that line. The foot's pitch is the normative shin angle less the ankle's
  // dorsiflexion, eased from the toe-off pitch over the first 20 % (over 40 %, the ankle stayed 5 deg more
  // plantarflexed through early swing) and into the heel-strike pitch over the last 40 %, so both ends join the
  // stance rockers exactly. It lands on the heel-strike pose (toes up), not on the flat footprint.
  struct Swing {
    glm::vec4 knots[kSwingKnots];  // ankle position (world) and foot pitch (rad, toes down) at each knot
    glm::quat from_yaw, to_yaw;
    AnklePose at(float sigma) const {
      const glm::vec4 k = cardinal_through(knots, sigma);
      const glm::quat heading = glm::slerp(from_yaw, to_yaw, smoothstep01((sigma - 0.25f) / 0.6f));
      return {glm::vec3(k), heading * pitch(k.w)};
    }
  };
  auto make_swing = [&](int leg, const glm::vec3& from, float from_heading, float from_pitch, const glm::vec3& to,
                        float to_heading, float start, float from_ground) {
    const AnklePose strike = stance_pose(rig, leg, to, to_heading, 0.0f, scale, style, nullptr, strike_pitch);
    const glm::vec3 chord = strike.position - from;
    float forward[kSwingKnots], up[kSwingKnots], shin_pitch[kSwingKnots];
    for (std::size_t k = 0; k < kSwingKnots; ++k) {
      // The subject's angles are a gait lab's; the rig's rotations are from its rest pose (LocomotionRig::rest_*).
      // Hip flexion is measured against the pelvis: the thigh's own turn is the hip's less the pelvis' forward tilt.
      const float thigh = glm::radians(kSwingHipDeg[k]) - rig.rest_hip_flexion - style.pelvis_anterior_tilt;
      const float knee = glm::radians(kSwingKneeDeg[k]) - rig.rest_knee_flexion;
      const glm::vec3 rel = pitch(-thigh) * rig.swing_leg[leg][k] * scale;
      forward[k] = rel.z, up[k] = rel.y;
      shin_pitch[k] = knee - thigh - (glm::radians(kSwingAnkleDeg[k]) - rig.rest_ankle_dorsiflexion);
    }
    // The hip covers the rest of the step: a short or stopping step keeps the legs' own motion.
    const float step = std::sqrt(chord.x * chord.x + chord.z * chord.z);
    const float hip_travel = std::max(step - (forward[kSwingKnots - 1] - forward[0]), 0.0f);
    const float along_last = hip_travel + forward[kSwingKnots - 1] - forward[0];
    const float pitch_from = from_pitch - shin_pitch[0];
    const float pitch_to = -strike_pitch - shin_pitch[kSwingKnots - 1];
    // The sole's ground level at both ends: under the toe tip at toe-off (the ground under the footprint it
    // leaves, `from_ground`: the rigid foot's tip at the toe-off pitch lies 3 cm below it, the toes being bent,
    // which let the clearance guard put the toe 3 mm into the ground at 0.8-0.9 m/s), under the landing footprint.
    const glm::vec3 tip_offset = (rig.tip_rest[leg] - rig.ankle_rest[leg]) * scale;
    const glm::vec3 heel_offset = (rig.heel_rest[leg] - rig.ankle_rest[leg]) * scale;
    const float ground_from = from_ground + tip_offset.y;
    const float ground_to = to.y + tip_offset.y;
    // Where the knots above assume the hip is: moving on by hip_travel, linearly from toe-off to heel strike. The
    // real hip moves at walking pace, so the foot is off the normative angles' path by e0 along the step at
    // toe-off (the rolled foot against the subject's toe-off angles) and by e1 at heel strike (the footprint's
    // lead against the subject's heel-strike angles). Spread linearly over the swing, as they were, e0 and e1 held
    // the foot 6-9 cm behind the normative path through late swing: the knee peaked and extended ~4 % of a cycle
    // late (50 deg at 88 % of the cycle, the subject's 37). Now e0 is made up in the first swing_catch_up of the
    // swing and e1 from swing_land_from on, and between them the foot follows the angles about the real hip.
    float e0 = 0.0f, e1 = 0.0f;
    if (style.swing_catch_up > 0.0f && step > 1e-4f) {
      const glm::vec3 along = glm::vec3(chord.x, 0.0f, chord.z) / step;
      const glm::vec3 facing = yaw(to_heading) * glm::vec3(0.0f, 0.0f, 1.0f);
      // The footprint holds the rest ankle `lead` ahead of the pelvis (footprint()); the hip is the rest hip.
      const float ankle_ahead_of_hip = (lead + (rig.ankle_rest[leg].z - rig.hip_rest[leg].z) * scale) *
                                           glm::dot(facing, along) + glm::dot(strike.position - to, along);
      const float limit = 0.15f * scale;  // a stopping or turning agent's step may fit the angles badly
      e1 = std::clamp(ankle_ahead_of_hip - forward[kSwingKnots - 1], -limit, limit);
      const float real_travel = track.speed * std::max(1.0f - start, 0.0f) * gp.cycle_time;
      e0 = std::clamp(e1 - (hip_travel - real_travel), -limit, limit);
    }
    const float lift_scale = std::max(1.0f - style.lift_long_step_drop * longer, 0.5f);
    Swing s;
    for (std::size_t k = 0; k < kSwingKnots; ++k) {
      const float sigma = static_cast<float>(k) / static_cast<float>(kSwingKnots - 1);
      float f = along_last > 1e-4f ? (hip_travel * sigma + forward[k] - forward[0]) / along_last : sigma;
      if (style.swing_catch_up > 0.0f && along_last > 1e-4f) {
        // The misfit e0 (1 - sigma) + e1 sigma of the linear spread becomes e0 a + e1 b; both ends stay put.
        const float a = 1.0f - smoothstep01(sigma / style.swing_catch_up);
        const float b = smoothstep01((sigma - style.swing_land_from) / std::max(1.0f - style.swing_land_from, 1e-3f));
        f += (e0 * (a - 1.0f + sigma) + e1 * (b - sigma)) / along_last;
      }
      const float lift = lift_scale * (up[k] - glm::mix(up[0], up[kSwingKnots - 1], f));
      const float p = shin_pitch[k] + pitch_from * (1.0f - smoothstep01(sigma / 0.2f)) +
                      pitch_to * smoothstep01((sigma - 0.6f) / 0.4f);
      glm::vec3 ankle = from + chord * f + kUp * lift;
      if (sigma > 0.2f && sigma < 0.8f) {
        // Clearance: the leg's angles are a person's, its lengths and the pelvis height are this walker's, so a
        // toe or heel may come out lower than the subject's 1-2 cm; such a knot in the middle of the swing is
        // raised until both clear the ground by swing_clearance. Guarding the knots at 12.5 and 87.5 % too
        // lifted the landing heel and left the knee 20 deg bent at 96 % of the cycle (subject: 3).
        const glm::quat q = glm::slerp(yaw(from_heading), yaw(to_heading), f) * pitch(p);
        const float sole = std::min((ankle + q * tip_offset).y, (ankle + q * heel_offset).y);
        ankle.y += std::max(glm::mix(ground_from, ground_to, f) + style.swing_clearance * scale - sole, 0.0f);
      }
      s.knots[k] = glm::vec4(ankle, p);
    }
    s.knots[0] = glm::vec4(from, from_pitch);
    s.knots[kSwingKnots - 1] = glm::vec4(strike.position, -strike_pitch);
    s.from_yaw = yaw(from_heading);
    s.to_yaw = yaw(to_heading);
    // Between the knots the spline and the foot's pitch can carry the toe below its knots' clearance, so the swing
    // is sampled every 5 % from 20 to 80 % and the two knots around each sample that passes too low are raised for
    // its shortfall (the least raise of the two that lifts the sample by it, were the spline linear between them),
    // up to four times over; most swings pass at the first. 24 samples measured the same clearance and cost the
    // locomotion system a third more time than 12 (25 walkers: 0.32 against 0.26 ms a frame).
    for (int pass = 0; pass < 4; ++pass) {
      float raise[kSwingKnots] = {};
      constexpr int kSamples = 12;
      for (int j = 0; j <= kSamples; ++j) {
        const float sigma = 0.2f + 0.6f * static_cast<float>(j) / kSamples;
        const AnklePose pose = s.at(sigma);
        const float sole = std::min((pose.position + pose.orientation * tip_offset).y,
                                    (pose.position + pose.orientation * heel_offset).y);
        const float shortfall = glm::mix(ground_from, ground_to, sigma) + style.swing_clearance * scale - sole;
        if (shortfall <= 0.0f) continue;
        const float x = sigma * static_cast<float>(kSwingKnots - 1);
        const auto k = std::min(static_cast<std::size_t>(x), kSwingKnots - 2);
        const float u = x - static_cast<float>(k);
        const float norm = (1.0f - u) * (1.0f - u) + u * u;
        if (k > 0) raise[k] = std::max(raise[k], shortfall * (1.0f - u) / norm);
        if (k + 2 < kSwingKnots) raise[k + 1] = std::max(raise[k + 1], shortfall * u / norm);
      }
      bool raised = false;
      for (std::size_t k = 1; k + 1 < kSwingKnots; ++k) {
        s.knots[k].y += raise[k];
        raised = raised || raise[k] > 0.0f;
      }
      if (!raised) break;
    }
    return s;
  };
  // A stance leg's hip `ahead` seconds from now at the pelvis' highest height, and the hip-ankle distance its
  // knee angle at tau gives (stance_pose's heel rise keeps to it).
  auto hip_hold = [&](int leg, float ahead, float tau) -> HipHold {
    const glm::vec3 hip = hip_position(rig, pelvis_motion(style, frac(phase + ahead / gp.cycle_time)), leg) +
                          glm::vec3(0.0f, style.heel_hold_height, 0.0f);
    return hip_hold_at(rig, pelvis_ahead(ahead), hip, leg, tau, scale);
  };

  // The leg phase a swinging leg's swing progresses from: the stance fraction, or where an early lift left.
  auto swing_start = [&](int leg) {
    const float early = g.leg(leg, kLegEarlyLift);
    return early >= 0.0f ? early : sf;
  };
  // A stance leg leaving the ground at leg phase psi, its stance at tau: it leaves from the pose the foot has (its
  // heel risen for the pelvis as last placed, see the end of this function, so the swing starts where the foot
  // is) and aims where the pelvis will be at heel strike plus the lead. `early`: begin_swing's.
  auto lift_off = [&](int leg, float psi, float tau, float pose_strike_pitch, float early) {
    const glm::vec3 plant{g.leg(leg, kLegPlantX), g.leg(leg, kLegPlantY), g.leg(leg, kLegPlantZ)};
    float p = 0.0f;
    const glm::vec3 last_root{lanes.root_translation.at(0, i), lanes.root_translation.at(1, i),
                              lanes.root_translation.at(2, i)};
    const HipHold hold =
        hip_hold_at(rig, pelvis, hip_at_root(rig, pelvis_motion(style, phase), last_root, leg), leg, tau, scale);
    const AnklePose from =
        stance_pose(rig, leg, plant, g.leg(leg, kLegPlantHeading), tau, scale, style, &p, pose_strike_pitch, &hold);
    const float strike_in = (1.0f - psi) * gp.cycle_time;
    const Pose2 to = landing_footprint(rig, track, strike_in, lead, leg, scale, gp.stance_time);
    begin_swing(g, leg, from.position, g.leg(leg, kLegPlantHeading), p, to.position, to.heading,
                track.distance_at(strike_in, lead), early);
  };
  // Agents: footprint `to` of swinging leg `leg` (heading to_heading) moved, if need be, to land within the leg's
  // reach of the hip for the pelvis at `at` as at gait phase `at_phase` (GaitStyle::land_within_reach).
  auto within_reach = [&](int leg, glm::vec3& to, float to_heading, const Pose2& at, float at_phase) {
    const AnklePose strike = stance_pose(rig, leg, to, to_heading, 0.0f, scale, style, nullptr, strike_pitch);
    const glm::vec3 beyond =
        beyond_reach(rig, style, leg, hip_position(rig, pelvis_motion(style, at_phase), leg),
                     WalkerFrame{at.position, at.heading, scale}.to_humanoid(strike.position), to_heading - at.heading,
                     scale);
    const glm::vec3 shift = yaw(at.heading) * beyond * scale;  // world, along the ground
    to.x += shift.x;
    to.z += shift.z;
  };
  // ---- Legs: footprint events, then each ankle goal (world, then humanoid space) ---------------------------
  AnklePose ankle[2];
  float toe_pitch[2] = {0.0f, 0.0f};
  for (int leg = 0; leg < 2; ++leg) {
    const float psi = frac(phase - 0.5f * static_cast<float>(leg));
    const bool swinging = g.leg(leg, kLegSwinging) > 0.5f;
    if (swinging && psi < 0.5f) {
      // Heel strike (the leg's phase wrapped): the swing target becomes the planted footprint, within reach of the
      // body as it is now (a swing cut short by stance_hurry lands here from anywhere in its last part).
      glm::vec3 to{g.leg(leg, kLegToX), g.leg(leg, kLegToY), g.leg(leg, kLegToZ)};
      if (source.agents() && style.land_within_reach) within_reach(leg, to, g.leg(leg, kLegToHeading), pelvis, phase);
      plant_foot(g, leg, to, g.leg(leg, kLegToHeading), g.leg(leg, kLegToDistance));
    } else if (!swinging && source.agents() && lanes.ik_flags.components != 0 &&
               (unreachable(lanes, leg, i) || (g.leg(1 - leg, kLegSwinging) < 0.5f && unreachable(lanes, 1 - leg, i)) ||
                std::abs(wrap_angle(g.leg(leg, kLegPlantHeading) - pelvis.heading)) > style.lift_twist) &&
               lifts_early(psi, sf, style)) {
      // Agents: a rolling stance foot the leg could not reach last frame, or twisted past lift_twist under a turning
      // body, lifts now (GaitStyle::early_lift), from the pose it has, and lands at the usual heel strike. The twist
      // is read now, not off IK's flags: its clamp yaws the foot in the very frame it binds.
      lift_off(leg, psi, psi / sf, strike_pitch, psi);
    } else if (!swinging && psi >= sf) {
      // Toe-off: leave from the rolled stance pose; aim where the pelvis will be at heel strike plus the lead.
      lift_off(leg, psi, 1.0f, 0.0f, -1.0f);
    } else if (swinging && source.agents() && psi < swing_start(leg) + style.retarget_until * (1.0f - swing_start(leg))) {
      // Agents: the swing foot re-aims at each frame's prediction through most of its swing, as a person adjusts a
      // step in flight. A target fixed at toe-off landed a turning walker's foot where the body would have been had
      // it gone straight, up to 1.4 m off its path by the end of that stance. The lane walk's predictions do not
      // change in flight, so it keeps the toe-off target (and its measured gait).
      const float strike_in = (1.0f - psi) * gp.cycle_time;
      const Pose2 to = landing_footprint(rig, track, strike_in, lead, leg, scale, gp.stance_time);
      g.leg(leg, kLegToX) = to.position.x;
      g.leg(leg, kLegToY) = to.position.y;
      g.leg(leg, kLegToZ) = to.position.z;
      g.leg(leg, kLegToHeading) = to.heading;
      g.leg(leg, kLegToDistance) = track.distance_at(strike_in, lead);
    } else if (swinging && source.agents() && style.land_within_reach) {
      // Past re-aiming, the target stays, but within reach of where the body will be at heel strike: a body held
      // back by the stance foot falls behind the prediction the target was aimed at. Moved a little each frame as
      // the body falls behind, the foot lands there without a last-frame jump.
      const float strike_in = (1.0f - psi) * gp.cycle_time;
      glm::vec3 to{g.leg(leg, kLegToX), g.leg(leg, kLegToY), g.leg(leg, kLegToZ)};
      within_reach(leg, to, g.leg(leg, kLegToHeading), pelvis_ahead(strike_in), 0.5f * static_cast<float>(leg));
      g.leg(leg, kLegToX) = to.x;
      g.leg(leg, kLegToZ) = to.z;
    }
  }
  // Agents: standing. A walker that wants to stand goes on stepping (its last steps land beside the other foot,
  // the lead shrinking with its speed) until both feet are down side by side; then it holds its phase and
  // settles, both feet flat, into an idle stance over idle_settle seconds. It leaves the stance as quickly when
  // it wants to move, and agent_move holds the body still until it has.
  float idle = 0.0f;
  if (source.agents()) {
    idle = g[kGaitIdle];
    if (agent_wants_to_stand(source.agent, i, style)) {
      const bool both_down = g.leg(0, kLegSwinging) < 0.5f && g.leg(1, kLegSwinging) < 0.5f;
      const glm::vec3 apart = glm::vec3(g.leg(0, kLegPlantX), 0.0f, g.leg(0, kLegPlantZ)) -
                              glm::vec3(g.leg(1, kLegPlantX), 0.0f, g.leg(1, kLegPlantZ));
      const float along = std::abs(glm::dot(apart, glm::vec3(std::sin(pelvis.heading), 0.0f, std::cos(pelvis.heading))));
      if (idle > 0.0f || (both_down && along < style.stand_feet_apart * scale))
        idle = std::min(1.0f, idle + dt / style.idle_settle);
    } else {
      idle = std::max(0.0f, idle - dt / style.idle_release);
    }
    g[kGaitIdle] = idle;
  }
  const float settle = smoothstep01(idle);  // 0 walking, 1 standing
  // The heel-strike pitch follows the step: the shin leans back less over a short step, and a fixed pitch left
  // the ankle 8.5 deg dorsiflexed at heel strike at 0.8 m/s. Shorter steps than 0.7 m (at rig scale) land with
  // the pitch scaled by the square of the step; longer ones keep the full pitch (scaling it up too pushed the
  // ankle to 10 deg at 1.8 m/s). Cadence eases slowly, so the pitch of a rolling heel changes smoothly and its
  // pivot stays put.
  // Agents: a stance foot the body has turned too far over pivots on the contact that carries it (the heel in
  // the heel rocker, the toe tip in the toe rocker), as a person pivots on the forefoot in a sharp turn. The contact stays where it is; the footprint kept is turned about it, so the next frames go on from
  // there. Without it the hip, knee and ankle ran out of twist and IK's clamp dragged the toe tip 15 mm sideways.
  // In between it never pivots: the turn rates keep its twist within bounds there, its footprint pointing where the
  // body faces at mid-stance.
  if (source.agents()) {
    for (int leg = 0; leg < 2; ++leg) {
      if (g.leg(leg, kLegSwinging) > 0.5f) continue;
      const float tau = std::min(frac(phase - 0.5f * static_cast<float>(leg)) / sf, 1.0f);
      // The foot may pivot only while one point carries it: the heel before foot flat, the toe tip once the toes
      // bend no further. Flat, or rolling over the ball with the toes down, it holds (both ball and tip would move).
      // Read off the pitch the foot had in the last frame, not the heel rise's schedule: the ankle's
      // plantarflexion limit may hold a foot below the schedule (stance_pose), and such a foot, on its ball,
      // pivoted about its tip slid the ball 5 cm (the crossing). Rolling on, it goes onto its tip in this frame
      // at the earliest and pivots from the next.
      const float roll = tau >= style.heel_off ? g.leg(leg, kLegStancePitch) : 0.0f;
      const bool on_heel = tau < style.heel_rocker, on_tip = roll > rig.toe_limit;
      const float heading = g.leg(leg, kLegPlantHeading);
      const float twist = wrap_angle(heading - pelvis.heading);
      if ((!on_heel && !on_tip) || std::abs(twist) <= style.max_foot_twist) continue;
      const glm::vec3 contact_rest = on_tip ? rig.tip_rest[leg] : rig.heel_rest[leg];
      const glm::vec3 plant{g.leg(leg, kLegPlantX), g.leg(leg, kLegPlantY), g.leg(leg, kLegPlantZ)};
      const glm::vec3 offset = (contact_rest - rig.ankle_rest[leg]) * scale;
      const glm::vec3 contact = plant + yaw(heading) * offset;
      const float turned = pelvis.heading + std::clamp(twist, -style.max_foot_twist, style.max_foot_twist);
      const glm::vec3 moved = contact - yaw(turned) * offset;
      g.leg(leg, kLegPlantX) = moved.x;
      g.leg(leg, kLegPlantY) = moved.y;
      g.leg(leg, kLegPlantZ) = moved.z;
      g.leg(leg, kLegPlantHeading) = turned;
    }
  }
  struct LegPath {
    bool swinging;
    float psi;
    float start;      // swing: the leg phase its swing progresses from (swing_start)
    glm::vec3 plant;  // stance: the footprint; swing: the one it lands on
    float plant_heading;
    std::optional<Swing> swing;  // swing: the current arc; stance: the predicted next one
  } legs[2];
  for (int leg = 0; leg < 2; ++leg) {
    LegPath& lp = legs[leg];
    lp.swinging = g.leg(leg, kLegSwinging) > 0.5f;
    lp.psi = frac(phase - 0.5f * static_cast<float>(leg));
    lp.start = swing_start(leg);
    if (lp.swinging) {
      lp.plant = {g.leg(leg, kLegToX), g.leg(leg, kLegToY), g.leg(leg, kLegToZ)};
      lp.plant_heading = g.leg(leg, kLegToHeading);
      lp.swing = make_swing(leg, {g.leg(leg, kLegFromX), g.leg(leg, kLegFromY), g.leg(leg, kLegFromZ)},
                            g.leg(leg, kLegFromHeading), g.leg(leg, kLegFromPitch), lp.plant, lp.plant_heading,
                            lp.start, g.leg(leg, kLegPlantY));  // the footprint left stays until heel strike
    } else {
      lp.plant = {g.leg(leg, kLegPlantX), g.leg(leg, kLegPlantY), g.leg(leg, kLegPlantZ)};
      lp.plant_heading = g.leg(leg, kLegPlantHeading);
      float p = 0.0f;
      const HipHold hold = hip_hold(leg, std::max(sf - lp.psi, 0.0f) * gp.cycle_time, 1.0f);
      const AnklePose from = stance_pose(rig, leg, lp.plant, lp.plant_heading, 1.0f, scale, style, &p, 0.0f, &hold);
      const float strike_in = (std::max(sf - lp.psi, 0.0f) + 1.0f - sf) * gp.cycle_time;
      const Pose2 to = landing_footprint(rig, track, strike_in, lead, leg, scale, gp.stance_time);
      lp.swing = make_swing(leg, from.position, lp.plant_heading, p, to.position, to.heading, sf, lp.plant.y);
    }
  }
  // `ahead` in seconds, at most ~0.3 cycle so a leg changes mode at most once.
  // `binds` (optional): whether the leg's reach holds the pelvis down, false for a swing foot between
  // kSwingFreeFrom and kSwingBindsFrom of its swing.
  auto ankle_at = [&](int leg, float ahead, float* foot_pitch, bool* binds = nullptr,
                      float* reach = nullptr) -> AnklePose {
    const LegPath& lp = legs[leg];
    const float psi = lp.psi + ahead / gp.cycle_time;  // not wrapped: > 1 means past the next heel strike
    if (foot_pitch) *foot_pitch = 0.0f;
    const bool in_swing = lp.swinging ? psi < 1.0f : psi >= sf;
    if (binds) *binds = true;
    if (reach) *reach = kReachUsed * rig.leg_reach[leg];
    if (!in_swing) {
      const float tau = std::min((lp.swinging ? psi - 1.0f : psi) / sf, 1.0f);
      // Through loading response and mid-stance the pelvis holds the stance knee at the subject's angle; later
      // the heel rise does (stance_pose), and the pelvis is held only by the straight leg.
      if (reach && tau < style.stance_knee_until) *reach = std::min(*reach, stance_target_reach(rig, leg, tau));
      if (tau < style.heel_hold_from)  // the hold starts later: spare the hip's pose
        return stance_pose(rig, leg, lp.plant, lp.plant_heading, tau, scale, style, foot_pitch, strike_pitch);
      const HipHold hold = hip_hold(leg, ahead, tau);
      return stance_pose(rig, leg, lp.plant, lp.plant_heading, tau, scale, style, foot_pitch, strike_pitch, &hold);
    }
    const float start = lp.swinging ? lp.start : sf;
    const float sigma = start < 1.0f ? std::clamp((psi - start) / (1.0f - start), 0.0f, 1.0f) : 1.0f;
    if (binds) *binds = sigma < kSwingFreeFrom || sigma >= kSwingBindsFrom;
    return lp.swing->at(sigma);
  };
  bool binds[2] = {true, true};
  float reach_now[2];
  for (int leg = 0; leg < 2; ++leg) ankle[leg] = ankle_at(leg, 0.0f, &toe_pitch[leg], &binds[leg], &reach_now[leg]);
  if (settle > 0.0f) {
    // Standing: each foot rolls from its place in stance at the held phase to flat on its footprint (a trailing
    // heel comes down about the ball, a landing forefoot rolls down about the heel), so the stance has both soles
    // on the ground. Moving along the stance's own rockers keeps the contact that carries the foot still;
    // blending the two ankle poses instead slid the ball and toe tip by up to 9 cm.
    const float flat_tau = 0.5f * (style.heel_rocker + style.heel_off);
    for (int leg = 0; leg < 2; ++leg) {
      if (legs[leg].swinging) continue;  // never while standing: it starts with both feet down
      const float tau = std::min(legs[leg].psi / sf, 1.0f);
      ankle[leg] = stance_pose(rig, leg, legs[leg].plant, legs[leg].plant_heading, glm::mix(tau, flat_tau, settle),
                               scale, style, &toe_pitch[leg], strike_pitch);
    }
  }

  // ---- Pelvis: sway, rotation and tilt, and the height both legs can reach -------------------------------
  // The pelvis goes as high as the nominal height allows, never higher than both legs reach, and smoothly: the
  // height is kept under parabolas (curvature bob_curvature) through every reach limit seen in the recent past
  // (the most binding one is kept with its age) and sampled ahead until the next foot event, whose poses are
  // already known. Taking the reach limit alone gave ~1 cm/frame kinks where a constraint started or stopped
  // binding; the parabolas turn those into smooth dips, lowest in double support as in a real gait.
  const PelvisMotion motion = pelvis_motion(style, phase, 1.0f - settle,
                                            settle * style.idle_sway * std::sin(kTwoPi * lanes.time.at(0, i) /
                                                                                style.idle_sway_period));
  glm::vec3 root_translation{motion.sway, style.pelvis_rise_max, 0.0f};
  const glm::vec3 ankle_world[2] = {ankle[0].position, ankle[1].position};
  if (source.agents()) {
    // Agents: a planted foot holds the body back. Avoidance may carry an agent further from a planted foot than
    // its leg reaches before that stance ends; the reach limits below would then drop the pelvis towards the
    // ground (a trace in the crossing: the root 0.7 m below standing, the hip level with the ankle it strained
    // for) and IK would drag the foot (foot slide up to 17 cm). Instead the body stays where each stance leg
    // still reaches its foot with the pelvis at most lag_dip below standing, off the agent by the difference
    // (kGaitLagX/Z, at most kBodyLagMax), which eases out (advance_gait_clock) once the foot lifts. The agent's own
    // position, the one avoidance keeps clear of others, is untouched: the body trails its disc by centimetres
    // for a moment. A foot that landed beyond reach ahead holds the body too (it is the body that fell behind).
    // Rejected: only feet behind the hip holding it (the crossing's largest slide 88 -> 117 mm: pushed back in
    // a jam, bodies recede from feet planted ahead; footprint_lead's backward step came later).
    glm::vec3 back(0.0f);  // humanoid units
    for (int leg = 0; leg < 2; ++leg) {
      if (legs[leg].swinging || !binds[leg]) continue;
      // Sideways as well (beyond_reach): a jam's sidesteps left bodies 42 cm to the side of a planted foot, the
      // toe tip 7 cm up (issue 16).
      back -= beyond_reach(rig, style, leg, hip_position(rig, motion, leg) + back,
                           frame.to_humanoid(ankle_world[leg]), legs[leg].plant_heading - pelvis.heading, scale);
    }
    if (back.x != 0.0f || back.z != 0.0f) {
      glm::vec3 shift = yaw(pelvis.heading) * back * scale;  // world
      // At most kBodyLagMax (scaled) off: a foot that held the body longer drags rather than the body leaving its disc
      // (the early lift and the hurry end such stances first).
      glm::vec2 lag = glm::vec2(g[kGaitLagX] + shift.x, g[kGaitLagZ] + shift.z);
      const float most = kBodyLagMax * scale;
      if (glm::length(lag) > most) {
        const glm::vec2 bounded = lag * (most / glm::length(lag));
        shift.x -= lag.x - bounded.x;
        shift.z -= lag.y - bounded.y;
        lag = bounded;
      }
      g[kGaitLagX] = lag.x;
      g[kGaitLagZ] = lag.y;
      pelvis.position += shift;
      window_end.position += shift;
      track.position += glm::vec2(shift.x, shift.z);
      frame.position = pelvis.position;
      lanes.placement.at(0, i) += shift.x;
      lanes.placement.at(2, i) += shift.z;
    }
  }
  if (settle > 0.0f) binds[0] = binds[1] = true;
  const float now_limit = reach_limit(rig, frame, motion, ankle_world, 1e9f, 0.0f, binds, reach_now);
  const float curvature = style.bob_curvature / scale;  // humanoid units
  g[kGaitDipAge] += dt;
  if (now_limit <= g[kGaitDipHeight] + curvature * g[kGaitDipAge] * g[kGaitDipAge]) {
    g[kGaitDipHeight] = now_limit;
    g[kGaitDipAge] = 0.0f;
  }
  // Samples sit on a fixed grid of gait phase, not at fixed offsets from now: a narrow dip then lands on the
  // same samples frame after frame instead of flickering between them (offset samples made 4 mm jumps).
  float future = 1e9f, future_ahead = 0.0f;
  constexpr float kSamplesPerCycle = 48.0f;
  // The pelvis' future placement is interpolated between now and the window's end: over the ~0.4 m it covers
  // a lane's curvature moves it by under a millimetre, and one path evaluation instead of one per sample cut
  // the system from 7 to ~4 us per walker. The final min with the exact current limit keeps reach guaranteed.
  // A standing walker's feet do not move: the reach now binds, nothing ahead (the walk's poses ahead would be
  // those of a held phase).
  for (float grid = std::floor(phase * kSamplesPerCycle) + 1.0f; settle <= 0.0f; grid += 1.0f) {
    const float ahead_cycles = grid / kSamplesPerCycle - phase;
    if (ahead_cycles > window) break;
    const float ahead = ahead_cycles * gp.cycle_time;
    const float at_phase = frac(phase + ahead_cycles);
    const Pose2 there = pelvis_ahead(ahead);
    bool binds_there[2];
    float reach_there[2];
    const glm::vec3 feet[2] = {ankle_at(0, ahead, nullptr, &binds_there[0], &reach_there[0]).position,
                               ankle_at(1, ahead, nullptr, &binds_there[1], &reach_there[1]).position};
    const float limit = reach_limit(rig, WalkerFrame{there.position, there.heading, scale},
                                    pelvis_motion(style, at_phase), feet, 1e9f, 0.0f, binds_there, reach_there);
    const float bound = limit + curvature * ahead * ahead;
    if (bound < future) future = bound, future_ahead = ahead;
  }
  const float past = g[kGaitDipHeight] + curvature * g[kGaitDipAge] * g[kGaitDipAge];
  // Blended, not a plain min: where the rising parabola of the last dip meets the falling one of the next, a
  // plain min leaves a corner (an 8 mm/frame change of vertical speed at 60 fps). The corner is rounded in
  // proportion to it: their slopes differ by 2 c (age + ahead), and a blend of width c (age + ahead)^2 turns it
  // at the same curvature. A fixed 2.5 cm blend also lowered the pelvis 6 mm wherever the two coincide (the
  // binding limit now and just ahead, at every mid-stance), which bent the stance knee 10 deg.
  const float span = g[kGaitDipAge] + future_ahead;
  const float envelope = smooth_min(past, future, std::clamp(curvature * span * span, 0.002f, 0.025f));
  root_translation.y = std::min(smooth_min(root_translation.y, envelope, 0.03f), now_limit);
  // Never lower than lag_dip below standing: a swing foot re-aimed beyond the leg's reach near its landing dropped
  // an agent's pelvis to the ground (0.6-0.7 m, the trace above); such a foot trails (IK clamps it) instead.
  root_translation.y = std::max(root_translation.y, -style.lag_dip / scale);
  // The loading response (the knee yielding ~20 deg after heel strike) comes from the stance angles the reach
  // limits hold (stance_knee_until). Rejected, measured: an extra bump subtracted after the limits (3 cm over
  // 35 % of a cycle made the yield before the stance angles; with them, 0.75 cm added 3 deg past the subject's
  // 23 and the knee RMS rose 7.3 -> 7.9 deg).
  lanes.root_translation.at(0, i) = root_translation.x;
  lanes.root_translation.at(1, i) = root_translation.y;
  lanes.root_translation.at(2, i) = root_translation.z;

  if (settle <= 0.0f) {
    // The stance heels rise for the pelvis as now placed, which the other leg's reach and the bob may hold lower
    // than the height the look-ahead assumed (heel_hold_height): the trailing knee then stays at the subject's
    // angle in double support instead of bending 15-25 deg while the pelvis comes down for the heel strike
    // (issue 21). The foot only rolls further about its own contacts, so it neither slides nor moves away
    // from the hip: the reach the pelvis was placed for still holds.
    for (int leg = 0; leg < 2; ++leg) {
      const float tau = std::min(legs[leg].psi / sf, 1.0f);
      if (legs[leg].swinging || tau < style.heel_hold_from) continue;
      const HipHold hold = hip_hold_at(rig, pelvis, hip_at_root(rig, motion, root_translation, leg), leg, tau, scale);
      ankle[leg] = stance_pose(rig, leg, legs[leg].plant, legs[leg].plant_heading, tau, scale, style, &toe_pitch[leg],
                               strike_pitch, &hold);
    }
  }
  // ---- Rotations the IK does not own: root, pelvis, spine counter-rotation, toes ---------------------------
  write_quat(lanes, rig.root, i, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  write_quat(lanes, rig.sacroiliac, i, motion.sacro);
  write_quat(lanes, rig.spine, i, yaw(-0.5f * motion.yaw));
  for (int leg = 0; leg < 2; ++leg) {
    write_quat(lanes, rig.ball[leg], i, pitch(-std::min(toe_pitch[leg], rig.toe_limit)));
    g.leg(leg, kLegStancePitch) = legs[leg].swinging ? 0.0f : toe_pitch[leg];
  }

  // ---- IK goals --------------------------------------------------------------------------------------------
  for (int leg = 0; leg < 2; ++leg) {
    glm::vec3 goal = frame.to_humanoid(ankle[leg].position);
    if (!binds[leg]) {
      // A swing foot the pelvis did not wait for is drawn in to the leg's reach (at a fast walk the normative
      // swing's nearly straight knee in late swing put it a few centimetres beyond): the foot trails a little
      // rather than the pelvis dropping for it (which made 1 cm/frame^2 jolts when the cadence changed).
      const glm::vec3 hip = hip_at_root(rig, motion, root_translation, leg);
      const glm::vec3 reach = goal - hip;
      const float most = kReachUsed * rig.leg_reach[leg], length = glm::length(reach);
      if (length > most) goal = hip + reach * (most / length);
    }
    write_goal(lanes, leg == 0 ? kLeftLeg : kRightLeg, i, goal, frame.to_humanoid(ankle[leg].orientation),
               IkMode::PositionOrientation);
    // Agents: a rolling stance foot in its early-lift window (both feet down) that IK cannot hold in this very
    // frame lifts now, from this pose, rather than next frame off IK's flags: in the frame the leg's limits first
    // bind, IK's clamp turns the foot about the ankle, and its toe tip moved 10-35 mm along the ground before the
    // lift (the crowds' largest slides in double support, issue 16). The swing then leaves from the pose the foot
    // has, as the early lift's does.
    if (source.agents() && style.lift_on_ik_miss && settle <= 0.0f && g.leg(leg, kLegSwinging) < 0.5f &&
        g.leg(1 - leg, kLegSwinging) < 0.5f) {
      const float psi = frac(phase - 0.5f * static_cast<float>(leg));
      if (lifts_early(psi, sf, style) && !stance_foot_holds(rig, lanes, i, leg))
        lift_off(leg, psi, psi / sf, strike_pitch, psi);
    }
  }
  const float swing_scale = std::clamp(reference_steps(gp, track, scale), 0.3f, 1.6f);
  for (int arm = 0; arm < 2; ++arm) {
    // Left arm back at left heel strike (phase 0), forward half a cycle later; the right arm the opposite.
    const float u = 4.0f * frac(phase + 0.5f * static_cast<float>(arm));
    const glm::vec3 p = rig.wrist_path[arm].point(u);
    const glm::vec3 rest = rig.wrist_rest[arm];
    // The upper body rides on the root translation (the pelvis bob and sway), so the wrist path does too.
    // A standing walker's arms ease back to hanging.
    const glm::vec3 swung(rest.x + swing_scale * (p.x - rest.x), p.y, rest.z + swing_scale * (p.z - rest.z));
    const glm::vec3 goal = root_translation + glm::mix(swung, rest, settle);
    write_goal(lanes, arm == 0 ? kLeftArm : kRightArm, i, goal, glm::quat(1.0f, 0.0f, 0.0f, 0.0f), IkMode::Position);
  }
}

}  // namespace

LocomotionRig make_locomotion_rig(const Skeleton& skeleton) {
  LocomotionRig rig;
  rig.skeleton = skeleton;
  rig.limbs = make_limbs(skeleton);
  for (int leg = 0; leg < 2; ++leg) {
    for (std::int32_t j = skeleton.parents[rig.limbs[leg == 0 ? kLeftLeg : kRightLeg].upper]; j >= 0; j = skeleton.parents[j])
      rig.hip_ancestors[leg].insert(rig.hip_ancestors[leg].begin(), j);
  }
  auto need = [&](const char* name) {
    const std::int32_t j = skeleton.find_joint(name);
    if (j < 0) throw std::invalid_argument(std::string("locomotion: skeleton '") + skeleton.name + "' has no " + name);
    return j;
  };
  rig.root = 0;
  // The joint the legs hang from. A rig whose pelvis is its root (Mixamo's Hips, a glTF skin named by shape) has no
  // separate sacroiliac: the root takes the pelvis's rotation too, so the spine turns with the pelvis there.
  rig.sacroiliac = skeleton.find_joint("sacroiliac");
  if (rig.sacroiliac < 0 && skeleton.parents[rig.limbs[kLeftLeg].upper] == 0) rig.sacroiliac = 0;
  if (rig.sacroiliac < 0) rig.sacroiliac = need("sacroiliac");
  rig.spine = skeleton.find_joint("vl5");
  // The ball of the foot, where the toes break: H-Anim 1.1's midtarsal (2019's transversetarsal) in the shipped
  // skeleton; a 2019 figure without it (Humanoid1 goes ankle -> metatarsophalangeal_2) breaks at the second toe's
  // MTP joint, and any other at the first joint below the ankle that lies 3 cm or more ahead of it.
  for (int leg = 0; leg < 2; ++leg) {
    const std::string side = leg == 0 ? "l_" : "r_";
    std::int32_t ball = -1;
    for (const char* stem : {"midtarsal", "metatarsophalangeal_2", "tarsometatarsal_2"})
      if (ball < 0) ball = skeleton.find_joint(side + stem);
    const std::int32_t ankle = rig.limbs[leg == 0 ? kLeftLeg : kRightLeg].lower;
    for (std::size_t c = static_cast<std::size_t>(ankle) + 1; ball < 0 && c < skeleton.joint_count(); ++c) {
      std::int32_t up = skeleton.parents[c];
      while (up > ankle) up = skeleton.parents[static_cast<std::size_t>(up)];
      if (up == ankle && skeleton.centers[c].z - skeleton.centers[ankle].z >= 0.03f) ball = static_cast<std::int32_t>(c);
    }
    if (ball < 0)
      throw std::invalid_argument("locomotion: skeleton '" + skeleton.name + "' has no " + side + "midtarsal (nor " +
                                  side + "metatarsophalangeal_2, nor any joint below " +
                                  skeleton.joint_names[static_cast<std::size_t>(ankle)] + " ahead of it)");
    rig.ball[leg] = ball;
  }
  rig.sacro_center = skeleton.centers[rig.sacroiliac];
  if (skeleton.parents[rig.limbs[kLeftLeg].upper] != rig.sacroiliac ||
      skeleton.parents[rig.limbs[kRightLeg].upper] != rig.sacroiliac)
    throw std::invalid_argument("locomotion: the hips of '" + skeleton.name + "' must hang from sacroiliac");
  for (int leg = 0; leg < 2; ++leg) {
    const LimbChain& limb = rig.limbs[leg == 0 ? kLeftLeg : kRightLeg];
    rig.hip_rest[leg] = skeleton.centers[limb.upper];
    rig.ankle_rest[leg] = skeleton.centers[limb.lower];
    rig.ball_rest[leg] = skeleton.centers[rig.ball[leg]];
    // The heel's ground contact: below the posterior calcaneus site where the skeleton has it, else a fifth of
    // the ankle-to-ball distance behind the ankle; at the ball's height (the sole's).
    const std::int32_t heel_site = skeleton.find_site(leg == 0 ? "l_calcaneous_post_pt" : "r_calcaneous_post_pt");
    glm::vec3 heel = heel_site >= 0 ? skeleton.sites[heel_site].position
                                    : rig.ankle_rest[leg] - 0.2f * (rig.ball_rest[leg] - rig.ankle_rest[leg]);
    heel.y = rig.ball_rest[leg].y;
    rig.heel_rest[leg] = heel;
    // The toe tip (the last contact before toe-off), on the ground ahead of the ball; without the site, 0.1 m
    // ahead of it along the foot.
    const std::int32_t tip_site = skeleton.find_site(leg == 0 ? "l_forefoot_tip" : "r_forefoot_tip");
    glm::vec3 along = rig.ball_rest[leg] - rig.ankle_rest[leg];
    along.y = 0.0f;
    glm::vec3 tip = tip_site >= 0 ? skeleton.sites[tip_site].position
                                  : rig.ball_rest[leg] + 0.1f * glm::normalize(along + glm::vec3(0, 0, 1e-6f));
    tip.y = rig.ball_rest[leg].y;
    rig.tip_rest[leg] = tip;
    // Reach is the farthest the knee's hinge range lets the ankle get, not |thigh| + |shin|: H-Anim's default
    // centres put the ankle 18 deg behind the knee line, and the knee may not hyperextend that far.
    const glm::vec3 thigh = skeleton.centers[limb.middle] - skeleton.centers[limb.upper];
    const glm::vec3 shin = skeleton.centers[limb.lower] - skeleton.centers[limb.middle];
    const JointLimits& knee = skeleton.limits[limb.middle];
    const float lo = knee.present ? knee.lower.x : -3.1f, hi = knee.present ? knee.upper.x : 3.1f;
    float reach = 0.0f;
    for (int k = 0; k <= 512; ++k) {
      const float theta = lo + (hi - lo) * static_cast<float>(k) / 512.0f;
      reach = std::max(reach, glm::length(thigh + glm::angleAxis(theta, limb.flexion_axis) * shin));
    }
    rig.leg_reach[leg] = reach;
    rig.thigh_length[leg] = glm::length(thigh);
    rig.shin_length[leg] = glm::length(shin);
    if (leg == 0) {
      // Sagittal angles (about +X) from the straight-down direction: a positive one swings a hanging segment back.
      auto back_from_down = [](const glm::vec3& v) { return std::atan2(-v.z, -v.y); };
      rig.rest_hip_flexion = -back_from_down(thigh);
      rig.rest_knee_flexion = back_from_down(shin) - back_from_down(thigh);
      rig.rest_ankle_dorsiflexion = back_from_down(shin);
    }
    for (std::size_t k = 0; k < kSwingKnots; ++k)
      rig.swing_leg[leg][k] = thigh + pitch(glm::radians(kSwingKneeDeg[k]) - rig.rest_knee_flexion) * shin;
    for (std::size_t k = 0; k < kStanceKnots; ++k) {
      // The subject's heel strike is 2 deg hyperextended; a hinge bent either way is as long, so read it as 1 deg.
      const float knee = glm::radians(std::max(kStanceKneeDeg[k], 1.0f)) - rig.rest_knee_flexion;
      rig.stance_reach[leg][k] = std::min(glm::length(thigh + pitch(knee) * shin), reach);
    }
  }
  const JointLimits& toe = skeleton.limits[rig.ball[0]];
  rig.toe_limit = toe.present ? std::max(-toe.lower.x, 0.0f) : 0.6f;
  const JointLimits& ankle = skeleton.limits[rig.limbs[kLeftLeg].lower];
  rig.ankle_plantarflexion_limit = ankle.present ? ankle.upper.x : 1.0f;
  rig.ankle_roll_limit = ankle.present ? std::max(std::min(-ankle.lower.z, ankle.upper.z), 0.0f) : 0.35f;
  const std::int32_t tip = skeleton.find_site("skull_tip");
  if (tip >= 0) {
    rig.rig_height = skeleton.sites[tip].position.y;
  } else {
    float top = 0.0f;
    for (const glm::vec3& c : skeleton.centers) top = std::max(top, c.y);
    rig.rig_height = top + 0.13f;
  }
  for (int arm = 0; arm < 2; ++arm) {
    const LimbChain& limb = rig.limbs[arm == 0 ? kLeftArm : kRightArm];
    const glm::vec3 shoulder = skeleton.centers[limb.upper];
    const glm::vec3 wrist = skeleton.centers[limb.lower];
    rig.wrist_rest[arm] = wrist;
    const float inward = arm == 0 ? -1.0f : 1.0f;  // towards the midline
    // Back, mid, front, mid, placed by the arm's own angles about the hanging pose: the upper arm swings about
    // the shoulder's transverse axis (flexion forward) and the elbow flexes a little behind the body, more in
    // front, as in normal walking (shoulder ~+-15-20 deg about hanging). Offsets are for a 0.7 m step; the system
    // scales their horizontal part. Rejected: fixed wrist offsets from the rest wrist (the old -8 / +11 cm), which
    // with the elbow bent to reach a raised knot put the upper arm behind the body through the whole cycle
    // (measured shoulder flexion -17..-1 deg).
    const glm::vec3 elbow = skeleton.centers[limb.middle];
    // The arm as it hangs. H-Anim rests with the arms down; a rig modelled in a T- or A-pose (most glTF and Mixamo
    // skins; CesiumMan's arms are level) would otherwise swing its arms out sideways: an upper arm more than 45 deg
    // from straight down is hung straight down, segment lengths kept.
    glm::vec3 upper_rest = elbow - shoulder, fore_rest = wrist - elbow;
    if (glm::dot(glm::normalize(upper_rest), glm::vec3(0, -1, 0)) < 0.7071f) {
      upper_rest = glm::vec3(0.0f, -glm::length(upper_rest), 0.0f);
      fore_rest = glm::vec3(0.0f, -glm::length(fore_rest), 0.0f);
      rig.wrist_rest[arm] = shoulder + upper_rest + fore_rest;
    }
    auto wrist_at = [&](float shoulder_flexion_deg, float elbow_flexion_deg, float inward_m) {
      const float sf = glm::radians(shoulder_flexion_deg), ef = glm::radians(elbow_flexion_deg);
      // pitch(-a) swings a hanging segment forward by a (H-Anim: +X is the character's left).
      const glm::quat upper = pitch(-sf);
      return shoulder + upper * upper_rest + (upper * pitch(-ef)) * fore_rest + glm::vec3(inward_m * inward, 0.0f, 0.0f);
    };
    std::vector<glm::vec3> knots = {wrist_at(-16.0f, 10.0f, 0.0f), wrist_at(1.0f, 16.0f, 0.004f),
                                    wrist_at(17.0f, 26.0f, 0.02f), wrist_at(1.0f, 16.0f, 0.004f)};
    // The return through the middle passes a little lower and further back than the forward swing, so the loop
    // does not fold onto itself (a closed Cardinal path through two equal points would have a zero-length
    // segment).
    knots[3] = wrist_at(-1.0f, 13.0f, 0.004f);
    rig.wrist_path[arm] = CardinalSpline(knots, 0.0f, true);
  }
  return rig;
}

namespace {

// Whether `columns` fit `rig` for walkers [0, count): widths, rows, every joint the system writes inside the
// rotations, no two views overlapping.
bool columns_fit(const LocomotionColumns& c, const LocomotionRig& rig, std::size_t count) {
  if (c.local_rotation.components == 0 || c.local_rotation.components % 4 != 0) return false;
  const std::size_t joints = c.local_rotation.components / 4;
  if (!c.path.fits(count, 1) || !c.gait.fits(count, kGaitFloats) || !c.time.fits(count, 1) ||
      !c.placement.fits(count, 5) || !c.root_translation.fits(count, 3) ||
      !c.local_rotation.fits(count, c.local_rotation.components) || !c.ik_goal.fits(count, kIkLimbs * kIkGoalFloats) ||
      !c.ik_mode.fits(count, kIkLimbs))
    return false;
  auto in_rig = [&](std::int32_t j, bool optional) {
    return (optional && j < 0) || (j >= 0 && static_cast<std::size_t>(j) < joints);
  };
  if (rig.limbs.size() != kIkLimbs || !in_rig(rig.root, false) || !in_rig(rig.sacroiliac, true) ||
      !in_rig(rig.spine, true) || !in_rig(rig.ball[0], true) || !in_rig(rig.ball[1], true) || !(rig.rig_height > 0.0f))
    return false;
  const ColumnView<const float> floats[] = {c.gait, c.time, c.placement, c.root_translation, c.local_rotation,
                                            c.ik_goal};
  for (std::size_t a = 0; a < std::size(floats); ++a) {
    if (floats[a].overlaps(c.path) || floats[a].overlaps(c.ik_mode)) return false;
    for (std::size_t b = a + 1; b < std::size(floats); ++b)
      if (floats[a].overlaps(floats[b])) return false;
  }
  return !c.path.overlaps(c.ik_mode);
}

// The walker state gait_parameters would otherwise throw on half-way through a frame: a height that is not
// positive and finite, or a cadence or cadence target that is not finite (the speed schedule's targets always
// are: cadence_for_speed clamps). Data, not layout, but cheap: three loads per walker against ~4 us of walking.
bool gait_state_valid(const ColumnView<float>& gait, std::size_t i) {
  const float height = gait.at(kGaitHeight, i);
  return height > 0.0f && std::isfinite(height) && std::isfinite(gait.at(kGaitCadence, i)) &&
         std::isfinite(gait.at(kGaitCadenceTarget, i));
}


// Path mode needs a path; agent mode (agent view set) needs the agent view's width and rows.
bool track_source_fits(const LocomotionColumns& c, std::span<const CardinalSpline> paths, std::size_t count) {
  if (c.agent.components == 0) return !paths.empty();
  return c.agent.fits(count, kAgentFloats) && (c.ik_flags.components == 0 || c.ik_flags.fits(count, kIkLimbs));
}

TrackSource track_source(const LocomotionColumns& c, std::span<const CardinalSpline> paths) {
  return {paths, c.path, c.agent};
}

}  // namespace

bool StartWalkingJob::validate() const {
  return rig && style && walker < path.count && columns_fit(*this, *rig, path.count) &&
         track_source_fits(*this, paths, path.count) && gait_state_valid(gait, walker);
}

bool StartWalkingJob::run() const {
  if (!validate()) return false;
  const LocomotionRig& rig = *this->rig;
  const GaitStyle& style = *this->style;
  const LocomotionColumns& lanes = *this;
  const std::size_t i = walker;
  GaitRef g{lanes.gait.base, lanes.gait.stride, i};
  const TrackSource source = track_source(lanes, paths);
  // The schedule at the walker's clock: 0 for a new walker, later for one restarting after it was an impostor.
  schedule_cadence(g, lanes.time.at(0, i), style);
  g[kGaitCadence] = std::clamp(g[kGaitCadenceTarget], kMinCadence, kMaxCadence);
  // The clock at dt = 0 gives the track and gait now without moving anything.
  const GaitClock clock = advance_gait_clock(rig, source, g, lanes.time.at(0, i), lanes.placement, i, 0.0f, style);
  const GaitParameters& gp = clock.gp;
  const GroundTrack& track = clock.track;
  const float scale = clock.scale;
  const float sf = gp.stance_fraction();
  const float lead = footprint_lead(track, gp, style, scale);
  // A standing agent has both feet down on their footprints, whatever its held phase.
  const bool standing = source.agents() && g[kGaitIdle] > 0.0f;
  for (int leg = 0; leg < 2; ++leg) {
    const float psi = frac(g[kGaitPhase] - 0.5f * static_cast<float>(leg));
    // The footprint of the last heel strike, psi cycles ago.
    const float ago = -psi * gp.cycle_time;
    const Pose2 plant = footprint(rig, track.at(ago, lead), leg, scale);
    plant_foot(g, leg, plant.position, plant.heading, track.distance_at(ago, lead));
    if (psi >= sf && !standing) {
      // The swing left (psi - sf) cycles ago, from the foot rolled for the hip then (at its highest height: the
      // walk's look-ahead assumes the same, see walk_one's hip_hold).
      const float since = (psi - sf) * gp.cycle_time;
      const Pose2 then = track.at(-since);
      const glm::vec3 hip = hip_position(rig, pelvis_motion(style, frac(g[kGaitPhase] - (psi - sf))), leg) +
                            glm::vec3(0.0f, style.heel_hold_height, 0.0f);
      const HipHold hold = hip_hold_at(rig, then, hip, leg, 1.0f, scale);
      float p = 0.0f;
      const AnklePose from = stance_pose(rig, leg, plant.position, plant.heading, 1.0f, scale, style, &p, 0.0f, &hold);
      const float strike_in = (1.0f - psi) * gp.cycle_time;
      const Pose2 to = landing_footprint(rig, track, strike_in, lead, leg, scale, gp.stance_time);
      begin_swing(g, leg, from.position, plant.heading, p, to.position, to.heading, track.distance_at(strike_in, lead));
    }
  }
  // No strike seen yet: a limit far in the past never binds; the prediction of the next strike does.
  g[kGaitDipHeight] = 0.0f;
  g[kGaitDipAge] = 10.0f;
  // Settle placement and goals for time "now" without advancing it.
  walk_one(rig, source, lanes, i, 0.0f, style);
  return true;
}

bool LocomotionJob::validate() const {
  if (!rig || !style || !std::isfinite(dt) || !columns_fit(*this, *rig, path.count) ||
      !track_source_fits(*this, paths, path.count))
    return false;
  for (std::size_t i = 0; i < path.count; ++i)
    if (!gait_state_valid(gait, i)) return false;
  return true;
}

bool LocomotionJob::run() const {
  if (!validate()) return false;
  constexpr std::size_t kChunk = 64;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, path.count, kChunk),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      const TrackSource source = track_source(*this, paths);
                      for (std::size_t i = r.begin(); i < r.end(); ++i) walk_one(*rig, source, *this, i, dt, *style);
                    },
                    tbb::simple_partitioner());
  return true;
}

bool GaitAdvanceJob::validate() const {
  if (!rig || !style || !std::isfinite(dt) || !(rig->rig_height > 0.0f)) return false;
  const std::size_t count = path.count;
  if (agent.components == 0 ? paths.empty() : !agent.fits(count, kAgentFloats)) return false;
  if (!gait.fits(count, kGaitFloats) || !time.fits(count, 1) || !placement.fits(count, 5)) return false;
  if (gait.overlaps(time) || gait.overlaps(placement) || time.overlaps(placement) || gait.overlaps(path) ||
      time.overlaps(path) || placement.overlaps(path))
    return false;
  for (std::size_t i = 0; i < count; ++i)
    if (!gait_state_valid(gait, i)) return false;
  return true;
}

bool GaitAdvanceJob::run() const {
  if (!validate()) return false;
  // Chunks 4x the walk's: a walker costs ~0.2 us here against ~3 us walking.
  constexpr std::size_t kChunk = 256;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, path.count, kChunk),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      const TrackSource source{paths, path, agent};
                      for (std::size_t i = r.begin(); i < r.end(); ++i) {
                        const GaitRef g{gait.base, gait.stride, i};
                        advance_gait_clock(*rig, source, g, time.at(0, i), placement, i, dt, *style);
                        if (source.agents()) {
                          // No feet to wait for: a far agent stands or walks as soon as it wants to.
                          g[kGaitIdle] = agent_wants_to_stand(agent, i, *style)
                                             ? std::min(1.0f, g[kGaitIdle] + dt / style->idle_settle)
                                             : std::max(0.0f, g[kGaitIdle] - dt / style->idle_release);
                        }
                      }
                    },
                    tbb::simple_partitioner());
  return true;
}

GaitAdvanceJob make_gait_advance_job(const LocomotionRig& rig, std::span<const CardinalSpline> paths,
                                     SoaTable& walkers, float dt, const GaitStyle& style, bool follow_agents) {
  GaitAdvanceJob job;
  job.path = u32_view(std::as_const(walkers), kWalkerPath);
  if (follow_agents) job.agent = f32_view(std::as_const(walkers), kWalkerAgent);
  job.gait = f32_view(walkers, kWalkerGait);
  job.time = f32_view(walkers, kWalkerClock).columns(0, 1);
  job.placement = f32_view(walkers, kWalkerPlacement);
  job.rig = &rig;
  job.paths = paths;
  job.style = &style;
  job.dt = dt;
  return job;
}

LocomotionColumns locomotion_columns(SoaTable& walkers, bool follow_agents) {
  LocomotionColumns c{u32_view(std::as_const(walkers), kWalkerPath),
          f32_view(walkers, kWalkerGait),
          f32_view(walkers, kWalkerClock).columns(0, 1),
          f32_view(walkers, kWalkerPlacement),
          f32_view(walkers, kWalkerRootTranslation),
          f32_view(walkers, kWalkerLocalRotation),
          f32_view(walkers, kWalkerIkGoal),
          i32_view(walkers, kWalkerIkMode),
          {},
          {}};
  if (follow_agents) {
    c.agent = f32_view(std::as_const(walkers), kWalkerAgent);
    c.ik_flags = u32_view(std::as_const(walkers), kWalkerIkFlags);
  }
  return c;
}

LocomotionJob make_locomotion_job(const LocomotionRig& rig, std::span<const CardinalSpline> paths, SoaTable& walkers,
                                  float dt, const GaitStyle& style, bool follow_agents) {
  return {locomotion_columns(walkers, follow_agents), &rig, paths, &style, dt};
}

StartWalkingJob make_start_walking_job(const LocomotionRig& rig, std::span<const CardinalSpline> paths,
                                       SoaTable& walkers, std::size_t walker, const GaitStyle& style,
                                       bool follow_agents) {
  return {locomotion_columns(walkers, follow_agents), &rig, paths, &style, walker};
}

}  // namespace strata
