#pragma once
// Retargeting BVH motion capture onto an H-Anim skeleton: an AnimationClip (rotation tracks for the mapped joints,
// a HumanoidRoot translation track) plus the feet's stance intervals, which systems/mocap_drive.h locks with IK.
//
// Method (per frame, world space of the BVH file, which for the CMU/Daz files already has H-Anim's axes: +Y up,
// the toes point +Z, the right side is -X):
//   1. BVH global rotations G_b from the channels (rest: every G_b = identity, bones along their OFFSETs).
//   2. For each mapped H-Anim joint h with BVH source b: R_h = G_b * Q_align(h), where Q_align rotates the H-Anim
//      rest bone direction (h -> its child) onto the BVH rest bone direction (b -> its child), by the shortest arc.
//      So every mapped H-Anim bone points where its BVH bone points, with the BVH's twist; this is where the T-pose
//      (BVH rest) versus arms-down (H-Anim rest) difference is compensated: Q_align of a shoulder is ~90 deg.
//      Unmapped H-Anim joints keep their parent's global rotation (identity local rotation).
//   3. local_h = R_parent(h)^-1 * R_h. Unmapped BVH joints (Buttock, the fingers, eyes) need no folding step: their
//      rotation is inside the global G_b of their mapped descendants and drops out of the local rotations.
//   4. Root position: the H-Anim hip midpoint is placed on the scaled BVH thigh midpoint, then lowered by the
//      capture floor's height (a line fitted through the planted feet, so a tilted floor is levelled) so the feet
//      touch y = 0 in stance, and moved horizontally so the clip starts at x = z = 0.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/mat3x3.hpp>

#include "components/animation_clip.h"
#include "components/skeleton.h"
#include "io/bvh.h"

namespace strata {

// One row of the name map. `hanim_aim` / `bvh_aim` name the child whose direction defines the bone (a joint or,
// for H-Anim, a site; an empty bvh_aim means the BVH joint's End Site). Both empty: no alignment (identity), the
// capture's rotation relative to its rest passed on as is; used for the root, spine, neck and head, which stand
// upright in both rest poses (retarget.cpp says why aiming their bones was wrong).
struct RetargetMapping {
  std::string bvh;
  std::string hanim;
  std::string bvh_aim;
  std::string hanim_aim;
  bool required = true;  // false: skipped when the BVH lacks the joint (e.g. toes, which many exports omit)
};

struct RetargetOptions {
  // Empty: recognised from the file's joint names (motion/bvh_naming.h: Poser/DAZ, CMU, Mixamo, HumanIK), with
  // the file's axes turned to H-Anim's. Given: used as is, with `axes` below (identity: H-Anim's already).
  std::vector<RetargetMapping> map;
  // With a given map: the file's axes -> H-Anim's, and the name reported as the family (bvh_naming_from_map of
  // motion/bvh_naming.h fills both from a map file).
  glm::mat3 axes{1.0f};
  std::string family;
  // Leading frames dropped. The CMU/Daz files start in the zero-rotation T-pose and ramp into the walk over frames
  // 0-4 (left shoulder Z: 0, -23, -46, -66, -79, -84 deg on frames 0..5, then it turns back): frame 5 is the first
  // walking frame. A fixed count rather than a detector: a detector needs a "walking" threshold that would be just
  // as file-specific, and the count is visible and overridable.
  int skip_frames = 5;
  // Stance detection on the retargeted, levelled feet (H-Anim metres): a foot is in stance while its heel
  // underside or its ball (see retarget.cpp) is below `stance_height` and moves horizontally slower than
  // `stance_speed` m/s (over +-speed_window frames). 5 cm: the fitted floor leaves +-1.5 cm of residual on this
  // capture and the heel of a just-struck foot sits 2-3 cm up. 0.8 m/s: a heel at strike or a ball at push-off
  // moves at 0.3-0.7 m/s, a swinging foot at 2-5 m/s.
  float stance_height = 0.05f;
  float stance_speed = 0.8f;
  int speed_window = 5;
  // Stance intervals separated by less than this (s) are one stance: the capture's jitter can split a stance,
  // while no swing is this short.
  float merge_gap = 0.15f;
  // Stance intervals shorter than this (s) are noise and dropped.
  float min_stance = 0.08f;
};

struct StanceInterval {
  float begin = 0.0f;  // seconds, clip time
  float end = 0.0f;    // exclusive
};

// Per leg (index kLeftLeg = 0, kRightLeg = 1 of systems/ik.h) the stance intervals, in time order.
struct FootContacts {
  std::array<std::vector<StanceInterval>, 2> legs;
  // Index of the interval holding clip time t, or -1 in swing.
  int stance_at(int leg, float t) const;
};

// A resolved map row: which BVH joint drives which H-Anim joint, and the rest alignment (identity for the
// rest-relative rows: root, spine, neck, head). The H-Anim joint's global rotation is G_bvh * align.
struct RetargetBone {
  std::int32_t hanim = -1;
  std::int32_t bvh = -1;
  glm::quat align{1, 0, 0, 0};
  bool aimed = false;          // aligned by bone direction (limbs) rather than rest-relative
  glm::vec3 hanim_dir{0.0f};   // aimed rows: unit H-Anim rest bone direction (joint -> its aim)
};

struct RetargetResult {
  AnimationClip clip;
  FootContacts contacts;
  float scale = 0.0f;           // metres per BVH unit (H-Anim leg length / BVH leg length)
  float ground_offset = 0.0f;   // metres added to the root height at z = 0 to put the feet on y = 0
  float floor_slope = 0.0f;     // dy/dz of the capture's floor that was levelled out (see retarget.cpp)
  int skipped_frames = 0;
  std::string family;           // the naming family recognised ("" with an explicit map)
  glm::mat3 axes{1.0f};         // the file's axes -> H-Anim's, applied to every frame
  std::vector<RetargetBone> bones;  // the map as resolved, in map order
  std::vector<std::string> unmapped_hanim;  // H-Anim joints that got no track (identity local rotation)
  std::vector<std::string> missing_on_rig;  // map rows left out because the rig lacks the joint (e.g. vt6)
  // Total horizontal root travel over the clip (last key - first key), metres.
  glm::vec3 root_travel{0.0f};
};

// Retargets `motion` onto `skeleton`. Throws std::invalid_argument when a map row names a joint missing in either
// (after the BVH's optional joints), the names match no known family, or the motion has too few frames.
RetargetResult retarget_bvh(const BvhMotion& motion, const Skeleton& skeleton, const RetargetOptions& options = {});

// Scalar FK of one pose: global rotations and joint positions in humanoid space (rest centres moved by the
// pose). A convenience for retargeting, tests and foot locking; the per-frame system is systems/fk.h.
void pose_globals(const Skeleton& skeleton, std::span<const glm::quat> local_rotations, const glm::vec3& root_translation,
                  std::span<glm::quat> global_rotations, std::span<glm::vec3> positions);

}  // namespace strata
