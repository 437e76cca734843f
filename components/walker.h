#pragma once
// The walker entity's hot per-frame columns, all in one SoaTable per rig (one row per walker), joint-major:
// component (j * k + c) of a per-joint field is one contiguous array over walkers, so the FK loop for joint j
// streams every walker with unit stride.
//
// Matrices are 3x4 affine, column-major: components [m00 m10 m20 | m01 m11 m21 | m02 m12 m22 | tx ty tz].
// The fourth row (0 0 0 1) is implicit; storing it would add a third more bandwidth for constants.
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec3.hpp>

#include "ecs/soa_table.h"

namespace strata {

inline constexpr std::uint32_t kAffineFloats = 12;
inline constexpr std::uint32_t kIkLimbs = 4;          // left leg, right leg, left arm, right arm (systems/ik.h)
// Per limb goal: position xyz (humanoid space), orientation quaternion xyzw (the lower joint's frame in humanoid
// space), swivel offset (rad), pole xyz (humanoid space; all zero = the rig's pole). The goal's mode (IkMode) is
// the integer field kWalkerIkMode, not a float here: a mode stored as 2.0f had to be decoded by range tests
// (> 1.5 && < 2.5) wherever it was read.
inline constexpr std::uint32_t kIkGoalFloats = 11;
enum IkGoalComponent : std::uint32_t {
  kGoalPx, kGoalPy, kGoalPz, kGoalQx, kGoalQy, kGoalQz, kGoalQw, kGoalSwivel, kGoalPoleX, kGoalPoleY, kGoalPoleZ
};
// Per limb result: position error (m). The flags (IkFlags) are the integer field kWalkerIkFlags.
inline constexpr std::uint32_t kIkResultFloats = 1;

// Locomotion state of a walking walker (systems/locomotion.h). World units (metres, radians) unless noted.
enum GaitComponent : std::uint32_t {
  kGaitDistance,        // distance travelled along the path (m), wrapped on closed paths
  kGaitPhase,           // gait cycle phase in [0, 1), left heel strike = 0
  kGaitCadence,         // current cadence (steps/min)
  kGaitCadenceTarget,   // cadence it eases towards (steps/min)
  kGaitHeight,          // body height (m)
                        // (the index of the path it follows is the integer field kWalkerPath)
  kGaitBaseSpeed,       // speed schedule: target speed = base * (1 + amplitude * sin(2 pi t / period + phase));
  kGaitSpeedAmplitude,  //   base <= 0 disables the schedule (kGaitCadenceTarget is then set by the caller)
  kGaitSpeedPhase,
  kGaitDipHeight,       // pelvis height limit (root translation y, humanoid units) at the last heel strike
  kGaitDipAge,          // seconds since that heel strike
  kGaitIdle,            // agents only: 0 walking .. 1 standing (feet together, flat, phase held); see locomotion.h
  kGaitLagX,            // agents only: the body's offset (m, world x and z) from the agent it follows, where
  kGaitLagZ,            //   a planted foot held it (locomotion.h GaitStyle::lag_dip), easing out; 0 otherwise
  kGaitLegs             // first per-leg component; leg l's component c is kGaitLegs + l * kLegFloats + c
};
enum LegComponent : std::uint32_t {
  kLegSwinging,                              // 1 while in swing
  kLegPlantX, kLegPlantY, kLegPlantZ, kLegPlantHeading,  // planted footprint: flat ankle pose (world)
  kLegFromX, kLegFromY, kLegFromZ, kLegFromHeading, kLegFromPitch,  // ankle pose at toe-off
  kLegToX, kLegToY, kLegToZ, kLegToHeading,  // swing target: the next footprint
  kLegToDistance,                            // path distance of the swing target
  kLegPlantDistance,                         // path distance of the planted footprint
  kLegEarlyLift,                             // agents: the leg phase an early swing left at (< 0: at toe-off)
  kLegStancePitch,                           // stance: the foot's heel-up pitch (rad) in the last frame
  kLegFloats
};
inline constexpr std::uint32_t kGaitFloats = kGaitLegs + 2 * kLegFloats;

// Foot locks of a mocap-driven walker (systems/mocap_drive.h), per leg: component kLock* + leg * kLockFloats.
// New rows read -1 everywhere: unlocked, in no stance interval.
enum FootLockComponent : std::uint32_t {
  kLockOn,        // > 0.5 while the foot's contact point is held at (x, y, z)
  kLockInterval,  // index of the clip's stance interval the lock belongs to, -1 in swing
  kLockX, kLockY, kLockZ,  // held contact point, world
  kLockPoint,     // which point of the foot is held: kContactHeel (0) until the foot rolls onto kContactBall (1)
  kLockFloats
};

// Steering agent of a scenario crowd (systems/navigation.h, systems/avoidance.h, systems/agent_move.h). A walker
// of a path crowd (the stadium track) leaves these at zero. Ground coordinates: x and z of the world, metres.
enum AgentComponent : std::uint32_t {
  kAgentPx, kAgentPz,            // position: the pelvis' point on the ground
  kAgentVx, kAgentVz,            // velocity it moved with this step (m/s), after turning and acceleration limits
  kAgentPrefVx, kAgentPrefVz,    // preferred velocity: navigation's output, avoidance's input
  kAgentOrcaVx, kAgentOrcaVz,    // avoidance's output: the collision-free velocity nearest the preferred one
                                 // (with kAgentMakeWay: the unit direction to step aside)
  kAgentHeading,                 // facing (rad about +Y, 0 = +Z), turned towards the velocity at a limited rate
  kAgentRadius,                  // disc radius (m)
  kAgentPrefSpeed,               // preferred walking speed (m/s)
  kAgentGoalX, kAgentGoalZ,      // the goal it walks to now
  kAgentGoalRadius,              // arrived within this distance (m)
  kAgentTargetX, kAgentTargetZ,  // the corner of its navigation path it steers at
  kAgentBestDistance,            // nearest it has been to its goal since the goal was set (m, along the way it knows;
                                 //   raised by as much when a path shows the way longer: systems/navigation.cpp)
  kAgentSinceProgress,           // seconds since it last came 0.25 m nearer (stuck detection)
  kAgentTravelTime,              // seconds since the goal was set
  kAgentReplanIn,                // seconds until its path is planned again (staggered over agents)
  kAgentFloats
};
// Integer agent state (U32): group in the scenario, waypoint index, flags, and the corners left of its path.
enum AgentIntComponent : std::uint32_t {
  kAgentGroup,     // spawn group (components/scenario.h)
  kAgentWaypoint,  // index of the goal within its group's waypoints; goals reached so far for random goals
  kAgentFlags,     // AgentFlag bits
  kAgentSeed,      // per-agent random state for random goals (xorshift)
  kAgentInts
};
enum AgentFlag : std::uint32_t {
  kAgentArrived = 1u,   // has reached its (final) goal at least once
  kAgentNeedsPath = 2u, // plan before steering: new goal or lost corridor
  kAgentPartialPath = 4u,  // the last plan ended short of the goal (unreachable)
  kAgentMakeWay = 8u,   // held still last step and pressed: kAgentOrcaVx/Vz is the direction to step aside
};
// Corners of the agent's current path, kAgentCorners of them (x, z), the first not yet reached first; the count is
// in kWalkerAgentCorners' last component.
inline constexpr std::uint32_t kAgentCorners = 4;

enum WalkerField : std::uint32_t {
  kWalkerPlacement,        // 5: ground position x, y, z (m), heading about +Y (rad), uniform scale (body height /
                           //    rig height); world = T(position) * Ry(heading) * S(scale) * humanoid space
  kWalkerClock,            // 2: animation time (s), playback rate (1 = real time)
  kWalkerClip,             // 1, I32: clip index, or kRestPose (-1) / kAllClips (-2) (systems/animation_sample.h)
  kWalkerLocalRotation,    // joints*4: local joint rotation quaternion x, y, z, w (identity at rest)
  kWalkerRootTranslation,  // 3: HumanoidRoot translation (m), H-Anim's Humanoid-space offset of the root
  kWalkerWorld,            // joints*12: F(j), the joint's frame in humanoid space (paper eq. 2)
  kWalkerSkinning,         // joints*12: F(j) A(j)^-1, rest humanoid space -> posed humanoid space (eq. 3)
  kWalkerIkGoal,           // kIkLimbs*kIkGoalFloats: limb goals, written by locomotion, read by IK
  kWalkerIkResult,         // kIkLimbs*kIkResultFloats: what IK achieved (position error)
  kWalkerIkMode,           // kIkLimbs, I32: each limb goal's IkMode (0 off, 1 position, 2 position + orientation)
  kWalkerIkFlags,          // kIkLimbs, U32: each limb's IkFlags from the last IK run
  kWalkerGait,             // kGaitFloats: locomotion state (GaitComponent, LegComponent)
  kWalkerPath,             // 1, U32: index of the path a walking walker follows (crowd.motion.paths, scene/crowd.h)
  kWalkerFootLock,         // 2*kLockFloats: mocap foot locks (FootLockComponent)
  kWalkerAgent,            // kAgentFloats: steering agent (AgentComponent)
  kWalkerAgentState,       // kAgentInts, U32: agent group, waypoint, flags, random state (AgentIntComponent)
  kWalkerAgentCorners,     // kAgentCorners*2 + 1: path corners (x, z) then their count
  // Muscle layer (systems/muscle.h), per action-line control point p of the rig's muscle set (P points; a rig
  // without muscles keeps one unused column per field, as a table field cannot be empty):
  kWalkerMusclePoint,      // P*3: control point position, humanoid space
  kWalkerMuscleFrame,      // P*6: local frame axes y (outward) then z (along the line); x = y cross z
  kWalkerMuscleLength,     // P: the point's length l (mean of its adjacent segments)
  kWalkerMuscleForce,      // P: force factor f = L / max(l, ratio L) - 1 (components/muscle.h)
  kWalkerFieldCount
};

// `muscle_points`: control points of the rig's muscle set (0, or >= 2 since a line has at least two).
// `agents`: the agent fields (kWalkerAgent, kWalkerAgentState, kWalkerAgentCorners) get their width; without it
// they are one unused column each.
std::unique_ptr<SoaTable> make_walker_table(std::string name, std::uint32_t joint_count,
                                            std::uint32_t muscle_points = 0, bool agents = false);

// A walker table with the same fields, of which only those a walker moving on without a pose needs have their
// width: placement, clock, clip, root translation, gait and path. Every other field is one unused column (a field
// cannot be empty). The impostors' table (scene/crowd.h): ~270 bytes a walker instead of a few kilobytes.
// Impostors of a scenario crowd keep steering: with `agents` the agent fields keep their width here too.
std::unique_ptr<SoaTable> make_light_walker_table(std::string name, bool agents = false);
// True when `table` was made by make_light_walker_table (its pose fields are one column wide).
bool is_light_walker_table(const SoaTable& table);

// Raw pointers into a walker table: component c of a field starts at base + c * stride. Valid until the table
// grows or shrinks. Kept for the readers not yet converted to job structs over ColumnViews (lod, gait metrics,
// pose gathering, the scalar references, tests); the converted systems take views (systems/job.h).
struct WalkerLanes {
  std::size_t count = 0;   // walkers
  std::size_t stride = 0;  // elements between components; >= count, a multiple of the SIMD lane count
  std::uint32_t joints = 0;
  float* placement = nullptr;
  float* clock = nullptr;
  float* local_rotation = nullptr;
  float* root_translation = nullptr;
  float* world = nullptr;
  float* skinning = nullptr;
  float* ik_goal = nullptr;
  float* ik_result = nullptr;
  float* gait = nullptr;
  float* foot_lock = nullptr;
  std::int32_t* clip = nullptr;
  std::uint32_t* path = nullptr;
  std::int32_t* ik_mode = nullptr;
  std::uint32_t* ik_flags = nullptr;
  std::uint32_t muscle_points = 0;  // 0 when the table was made without muscles
  float* muscle_point = nullptr;
  float* muscle_frame = nullptr;
  float* muscle_length = nullptr;
  float* muscle_force = nullptr;

  float* at(float* base, std::size_t component) const { return base + component * stride; }
};

WalkerLanes walker_lanes(SoaTable& table, std::uint32_t joint_count);

// A walker's placement as a transform from its humanoid space to the world: T(position) Ry(heading) S(scale).
// Heading h turns +Z (the humanoid's forward) to (sin h, 0, cos h).
struct Placement {
  glm::vec3 position{0.0f};
  float cos_heading = 1.0f, sin_heading = 0.0f, scale = 1.0f;

  glm::vec3 direction(const glm::vec3& d) const {
    return {cos_heading * d.x + sin_heading * d.z, d.y, -sin_heading * d.x + cos_heading * d.z};
  }
  glm::vec3 point(const glm::vec3& p) const { return position + direction(scale * p); }
};

inline Placement placement_of(const WalkerLanes& lanes, std::size_t walker) {
  const std::size_t s = lanes.stride;
  const float heading = lanes.placement[3 * s + walker];
  return {{lanes.placement[0 * s + walker], lanes.placement[1 * s + walker], lanes.placement[2 * s + walker]},
          std::cos(heading), std::sin(heading), lanes.placement[4 * s + walker]};
}

}  // namespace strata
