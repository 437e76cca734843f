#pragma once
// IK system: analytic 7-DOF limb IK (IKAN's SRS chain, Tolani, Goswami & Badler 2000; maths in
// ../shared/notes/tech-brief.md section 1, implemented here from the equations) for both arms and both legs of
// every walker. Upper joint (shoulder/hip) 3 DOF, middle (elbow/knee) 1 DOF about its flexion axis, lower
// (wrist/ankle) 3 DOF. The swivel angle of the middle joint about the upper->goal axis is set from a pole
// direction (knees forward, elbows back) and moved to the nearest feasible swivel when joint limits forbid it.
//
// Runs after locomotion (which writes goals, the root and spine rotations) and before FK, whose input rotations
// it overwrites for the limb joints.
//
//   reads:  skeleton (hierarchy, centres, limits), limbs, ik_goal (kIkLimbs*kIkGoalFloats), ik_mode (kIkLimbs,
//           I32), root_translation (3), local_rotation of the limbs' ancestors (joints*4)
//   writes: local_rotation of each solved limb's three joints, ik_error (kIkLimbs), ik_flags (kIkLimbs, U32)
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include "components/skeleton.h"
#include "ecs/column_view.h"
#include "systems/job.h"

namespace strata {

// One limb of a rig, built once from the skeleton (immutable rig data).
struct LimbChain {
  std::string name;                 // "l_leg", "r_leg", "l_arm", "r_arm"
  std::int32_t upper = -1;          // hip / shoulder joint index
  std::int32_t middle = -1;         // knee / elbow
  std::int32_t lower = -1;          // ankle / wrist
  glm::vec3 flexion_axis{1, 0, 0};  // the middle joint's hinge axis in rest (humanoid) axes; a positive angle about
                                    // it flexes (knee: +X, elbow: -X, see data/default_skeleton.x3d)
  glm::vec3 pole{0, 0, 1};          // where the middle joint should point, rest axes of the upper joint's parent:
                                    // knees forward (+Z), elbows back (-Z); a walker may override per frame
};

enum LimbIndex : std::uint32_t { kLeftLeg, kRightLeg, kLeftArm, kRightArm, kLimbCount };

// The four limbs of an H-Anim skeleton by joint name (l/r_hip-knee-ankle, l/r_shoulder-elbow-wrist).
// Throws std::invalid_argument naming the first missing joint.
std::vector<LimbChain> make_limbs(const Skeleton& skeleton);

// ---- Single-limb solver (pure maths; the system calls it per walker and limb) ---------------------------------

// Goal modes (the walker's ik_mode field, one integer per limb).
enum class IkMode : std::uint8_t { Off = 0, Position = 1, PositionOrientation = 2 };

// Result flags, OR-ed (the walker's ik_flags field, one integer per limb).
enum IkFlags : std::uint32_t {
  kIkReached = 1u << 0,            // the end effector is on the goal (within 1e-5 m)
  kIkUnreachable = 1u << 1,        // goal beyond reach (or inside the inner reach): clamped just inside, flagged
  kIkSwivelMoved = 1u << 2,        // the requested swivel violated limits; the nearest feasible swivel was taken
  kIkLimitsInfeasible = 1u << 3,   // no swivel satisfies the limits: least-violation configuration, flagged
  kIkOrientationClamped = 1u << 4, // the lower joint's rotation needed for the orientation goal broke its limits
  kIkInvalidInput = 1u << 5,       // a non-finite goal, orientation, pole or swivel offset: a non-finite goal leaves
                                   // the limb at rest (solve_limb) or untouched (IkJob); the others are ignored
};

struct LimbSolveInput {
  // Effector goal (the lower joint's centre) in the upper joint's PARENT frame, expressed as if that parent were
  // at rest: i.e. humanoid rest coordinates, where the upper joint sits at its rest centre.
  glm::vec3 goal{0.0f};
  IkMode mode = IkMode::Position;
  // PositionOrientation: the desired rotation of the lower joint's frame, same frame as `goal` (R1*Rm*R2).
  glm::quat orientation{1, 0, 0, 0};
  glm::vec3 pole{0, 0, 1};     // preferred middle-joint direction, same frame
  float swivel_offset = 0.0f;  // radians added to the pole's swivel (0 = middle joint in the goal-pole plane)
};

struct LimbSolveResult {
  glm::quat upper{1, 0, 0, 0};   // local rotations to write into the three joints
  glm::quat middle{1, 0, 0, 0};
  glm::quat lower{1, 0, 0, 0};
  float swivel = 0.0f;           // the swivel angle taken, radians
  float position_error = 0.0f;   // |effector - requested goal| in metres after solving (0 when reached)
  std::uint32_t flags = 0;
};

LimbSolveResult solve_limb(const Skeleton& skeleton, const LimbChain& limb, const LimbSolveInput& input);

// ---- One limb as the system sees it ----------------------------------------------------------------------------
// The two steps between a walker's columns and solve_limb, shared by the system and by anything that must know
// ahead what the system will answer (locomotion's stance_foot_holds asks before lifting a foot), so the two cannot
// drift apart: the same inputs give the same flags, bit for bit.

// A joint's frame in humanoid space for one walker's pose: the point p, given in the rest coordinates of the
// joint's children, is at m * p + g. Double precision, as the system composes it.
struct JointFrame {
  glm::dmat3 m{1.0};
  glm::dvec3 g{0.0};
};

// Joint `joint`'s frame for walker i: its local rotation (local_rotation, joints*4, x y z w; need not be unit) about
// its rest centre, composed onto its parent's frame `parent`; the root (no parent) rides on root_translation (3).
JointFrame joint_frame(const Skeleton& skeleton, std::int32_t joint, const JointFrame& parent,
                       const ColumnView<const float>& local_rotation, const ColumnView<const float>& root_translation,
                       std::size_t i);

// What limb `limb_index` of walker i asks: Off (its mode neither Position nor PositionOrientation: the limb is left
// alone), InvalidGoal (a non-finite goal position: left as animation posed it), or Solve with `input` filled from
// its goal slot (ik_goal, kIkLimbs*kIkGoalFloats) turned from humanoid space into `parent`, the frame of the upper
// joint's parent (for an upper joint that is the root: identity at root_translation, which the caller gives).
enum class LimbRequest : std::uint8_t { Off, InvalidGoal, Solve };
LimbRequest limb_solve_input(const LimbChain& limb, std::uint32_t limb_index, const JointFrame& parent,
                             const ColumnView<const float>& ik_goal, const ColumnView<const std::int32_t>& ik_mode,
                             std::size_t i, LimbSolveInput& input);

// ---- The system --------------------------------------------------------------------------------------------

// Per walker and limb, reads the goal (components/walker.h: position in humanoid space, orientation, swivel
// offset, pole) and its mode, computes the limb's parent frame from the walker's current local rotations (the
// ancestors of the upper joint, e.g. root, sacroiliac, spine), solves, and writes the three joints' local
// rotations, the flags and the position error. A mode other than 1 or 2 reads as Off: the limb keeps its
// rotations and gets flags 0, error 0. Walkers are independent: oneTBB chunks, output identical for any thread
// count.
struct IkJob {
  const Skeleton* skeleton = nullptr;
  std::span<const LimbChain> limbs;             // limb k's goal is goal slot k (make_limbs order)
  ColumnView<const float> ik_goal;              // kIkLimbs*kIkGoalFloats (IkGoalComponent per limb)
  ColumnView<const std::int32_t> ik_mode;       // kIkLimbs: IkMode per limb
  ColumnView<const float> root_translation;     // 3
  ColumnView<float> local_rotation;             // joints*4: ancestors read, limb joints written
  ColumnView<float> ik_error;                   // kIkLimbs*kIkResultFloats: |effector - goal| (m)
  ColumnView<std::uint32_t> ik_flags;           // kIkLimbs: IkFlags

  // Skeleton set (parents before children, at most kMaxJointsPerRig joints); 1..kIkLimbs limbs whose joints
  // are in the skeleton and form a chain; every view with the same rows and its width; outputs not overlapping
  // each other or an input.
  bool validate() const;
  bool run() const;
};

// The job over every walker of `walkers` (a walker table, components/walker.h).
IkJob make_ik_job(const Skeleton& skeleton, std::span<const LimbChain> limbs, SoaTable& walkers);

}  // namespace strata
