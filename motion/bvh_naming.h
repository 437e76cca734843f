#pragma once
// Which motion-capture skeleton a BVH file holds, told from its joint names, and the map that retargets it onto
// the 25-joint H-Anim skeleton (motion/retarget.h). The families recognised:
//   Poser/DAZ          hip, abdomen, chest, neck, head, lCollar, lShldr, lForeArm, lHand, lThigh, lShin, lFoot, lToe
//   CMU (MotionBuilder) Hips, LowerBack, Spine, Spine1, Neck, Neck1, Head, LHipJoint, LeftUpLeg, LeftLeg, LeftFoot,
//                      LeftToeBase, LeftShoulder, LeftArm, LeftForeArm, LeftHand
//   CMU (3ds Max)      as above with LeftHip, LeftKnee, LeftAnkle, LeftToe for the leg
//   Mixamo             mixamorig:Hips, Spine, Spine1, Spine2, Neck, Head, LeftUpLeg, LeftLeg, LeftFoot, ...
//   HumanIK            Hips, Spine, Spine1..., Neck, Head, LeftUpLeg, LeftLeg, LeftFoot, LeftToeBase, ...
// Names compare without case and without a namespace prefix ("mixamorig:", "Character1_" is not stripped).
// The spine maps by position in the chain, not by name: vl5 takes the lowest spine joint, vt6 the one the neck
// hangs from, so Spine1 is the chest in a CMU file and Spine2 in a Mixamo one; joints between them fold into the
// upper one (retargeting reads global rotations).
//
// The file's axes are found from its rest pose (left hip minus right hip, root up to the neck) and snapped to the
// nearest signed permutation of H-Anim's (+X left, +Y up, +Z forward), so Z-up and X-forward files retarget as
// well; units are inferred from the rest pose's stature.
#include <string>
#include <vector>

#include <glm/mat3x3.hpp>

#include "components/humanoid_shape.h"  // normalised_joint_name, the families' names
#include "io/bvh.h"
#include "io/retarget_map_file.h"
#include "motion/retarget.h"

namespace strata {

struct BvhNaming {
  std::string family;                  // "Poser/DAZ", "CMU (MotionBuilder)", "CMU (3ds Max)", "Mixamo", "HumanIK",
                                       // "by shape (...)" or "map FILE"
  std::vector<RetargetMapping> map;    // onto the 25-joint H-Anim skeleton
  glm::mat3 axes{1.0f};                // file axes -> H-Anim axes (a rotation, signed permutation of the axes)
  float stature = 0.0f;                // rest pose's height, file units (lowest to highest joint or end site)
  std::string units;                   // "metres", "centimetres", "inches" or "unknown"
  float metres_per_unit = 0.0f;        // for the units above; 0 when unknown
};

// Recognises the naming family of `motion` and builds its map; names it does not know are read by the skeleton's
// shape instead (family "by shape ..."; bvh_naming.cpp says how). Throws std::invalid_argument with one line naming
// the H-Anim joints no BVH joint name matched, why the shape could not be read, and how to pass a map file.
BvhNaming recognise_bvh_naming(const BvhMotion& motion);

// The map a retarget map file gives (io/retarget_map_file.h), with each row's aim and the file's axes and units
// worked out as for a recognised family. Throws LoadError "MAPFILE:LINE: ..." for a BVH joint the capture lacks,
// and "MAPFILE: ..." for rows whose joints do not hang one below the other as the H-Anim ones do.
BvhNaming bvh_naming_from_map(const BvhMotion& motion, const RetargetMapFile& file);

// The rotation from a BVH file's axes to H-Anim's, from its rest pose's left direction (left hip minus right hip)
// and up direction (root to neck), each snapped to the nearest signed axis; identity when they are degenerate.
glm::mat3 bvh_file_axes(const glm::vec3& left, const glm::vec3& up);


}  // namespace strata
