#pragma once
// Mocap drive: plays a retargeted motion-capture clip (motion/retarget.h) on walkers so that they keep walking
// forward across loops, and locks each foot where it landed for as long as the clip says it is in stance, by
// writing leg goals for the IK system (systems/ik.h).
//
// Frame order for mocap walkers: MocapDriveJob (clock, pose, root motion, leg goals) -> IkJob -> FkJob.
// It replaces AnimationJob for them: it advances the walker clock itself.
//
//   reads:  rig (skeleton, clip, stance intervals, limbs, loop displacement, reach), dt, rate (clock component 1),
//           placement heading and scale
//   writes: time (clock component 0), placement position (advanced per loop), foot_lock (2*kLockFloats, read and
//           written), local_rotation (joints*4), root_translation (3), ik_goal of the legs, ik_mode (all limbs)
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "components/animation_clip.h"
#include "components/skeleton.h"
#include "ecs/column_view.h"
#include "motion/retarget.h"
#include "systems/ik.h"
#include "systems/job.h"

namespace strata {

// Immutable per rig: the skeleton, the clip and its stance intervals (referenced, not copied: they outlive the
// MocapRig), the limbs, and the clip's root displacement per loop (last key - first key, horizontal).
struct MocapRig {
  const Skeleton* skeleton = nullptr;
  const AnimationClip* clip = nullptr;
  const FootContacts* contacts = nullptr;
  std::vector<LimbChain> limbs;
  glm::vec3 loop_displacement{0.0f};
  float reach[2] = {0.0f, 0.0f};  // per leg: the farthest hip-ankle distance a lock may need (see below)
  // Per leg, the foot's two ground contacts relative to the ankle in the rest pose (humanoid axes): the heel's
  // underside and the ball (systems/locomotion.h's heel_rest and ball_rest). They ride on the ankle's frame.
  glm::vec3 heel_offset[2] = {glm::vec3(0.0f), glm::vec3(0.0f)};
  glm::vec3 ball_offset[2] = {glm::vec3(0.0f), glm::vec3(0.0f)};
};
inline constexpr float kContactHeel = 0.0f;
inline constexpr float kContactBall = 1.0f;
// A lock is released once it is farther from the hip than this fraction of the leg's longest reach (knee as
// straight as its limit allows): 0.5 % short of the shell keeps the solve exact rather than clamped.
inline constexpr float kMocapReachFraction = 0.995f;
MocapRig make_mocap_rig(const Skeleton& skeleton, const AnimationClip& clip, const FootContacts& contacts);

// For every walker: clock += dt * rate, wrapped into [0, duration) with the walker's placement advanced by the
// loop's root displacement (rotated by its heading, times its scale) per wrap; the clip sampled into the local
// rotations and root translation; and per leg in stance an IK goal (mode PositionOrientation, the clip's ankle
// orientation) that holds the foot's contact point where it touched down. The contact is the heel from heel strike
// until the clip's ball sinks below its heel (foot flat onward), then the ball, re-anchored where the held foot puts
// it, so the switch is seamless. The ankle goal is the held point plus the clip's ankle-from-contact offset: the
// ankle rolls over the heel and then over the ball as captured, and only the contact point is pinned. Holding the
// ankle where it landed was the first design; it made IK bend the knee up to 10 deg away from the capture while
// the captured ankle rolled forward over the heel. Mode Off in swing and for the arms. A lock is released for the
// rest of its stance once the ankle goal leaves the leg's reach (see kMocapReachFraction); the foot then follows the
// clip (no blend). A wrap releases the locks: the clip is not a seamless cycle, so a lock from the previous loop's
// last frames would not fit the next loop's pose.
// The lock state lives in the walker's foot_lock columns (components/walker.h), so it moves with the walker
// when the table swap-removes. Walkers run one after another (as before the job: ~1 us each).
struct MocapDriveJob {
  const MocapRig* rig = nullptr;
  float dt = 0.0f;
  ColumnView<const float> rate;        // 1: playback rate
  ColumnView<float> time;              // 1: clip time (s), read, advanced and wrapped
  ColumnView<float> placement;         // 5: heading and scale read; position advanced by whole loops
  ColumnView<float> foot_lock;         // 2*kLockFloats: FootLockComponent per leg, read and written
  ColumnView<float> local_rotation;    // joints*4
  ColumnView<float> root_translation;  // 3
  ColumnView<float> ik_goal;           // kIkLimbs*kIkGoalFloats: the legs' goals written when locked
  ColumnView<std::int32_t> ik_mode;    // kIkLimbs: every limb's mode written

  // Rig complete (skeleton at most kMaxJointsPerRig joints, clip, contacts, both leg limbs in the skeleton);
  // dt finite; every view with the same rows and its width; no two views overlapping.
  bool validate() const;
  bool run() const;
};

// The job over every walker of `walkers` (a walker table, components/walker.h).
MocapDriveJob make_mocap_drive_job(const MocapRig& rig, SoaTable& walkers, float dt);

}  // namespace strata
