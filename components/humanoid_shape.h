#pragma once
// Finding a humanoid's joints from its skeleton's shape alone, whatever the joints are called: for motion captures
// whose names no family uses (motion/bvh_naming.h) and for rigs with names of their own, or none (a glTF skin such
// as CesiumMan, whose joints are unnamed). Works on any tree given in topological order (parents[j] < j) with
// rest positions; humanoid_shape.cpp says how each joint is told.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

namespace strata {

struct Skeleton;

struct HumanoidShape {
  struct Side {
    std::int32_t collar = -1, shoulder = -1, elbow = -1, wrist = -1, hip = -1, knee = -1, ankle = -1, toe = -1;
    std::int32_t hand_aim = -1;  // by name only: the middle finger's base, the hand's direction (-1 when absent)
  };
  std::int32_t pelvis = -1;  // where the legs and the spine branch
  std::int32_t vl5 = -1;     // lowest spine joint above the pelvis (-1 when the neck hangs straight off it)
  std::int32_t vt6 = -1;     // the chest, where the neck and arms branch (-1 with fewer than two spine joints)
  std::int32_t neck = -1, head = -1;
  Side sides[2];             // left, right
  bool facing_assumed = false;  // the feet showed no forward direction: the figure was taken to face +Z
};

// Reads the shape. `tips[j]` is where joint j's bone ends (a BVH End Site, in the same space as `rest`), equal to
// rest[j] where there is none; `tips` may be empty. Returns an empty string on success, else why the shape is not
// a humanoid's (one clause, for an error message).
std::string find_humanoid_by_shape(std::span<const std::int32_t> parents, std::span<const glm::vec3> rest,
                                   std::span<const glm::vec3> tips, HumanoidShape& out);

// A name as compared: lower case, without anything up to a ':' (Mixamo's "mixamorig:" and the like).
std::string normalised_joint_name(std::string_view name);

// Finds the joints by the names motion-capture and rigging tools give them (motion/bvh_naming.h lists the
// families: Poser/DAZ, CMU in both forms, Mixamo, HumanIK and other Left/Right names). The spine goes by position:
// vl5 is the lowest joint between the pelvis and the neck, vt6 the one the neck hangs from. Returns the H-Anim
// names of the joints no name matched (empty on success, `out` then filled and `family` naming the family).
std::vector<std::string> find_humanoid_by_names(std::span<const std::int32_t> parents,
                                                std::span<const std::string> names, HumanoidShape& out,
                                                std::string& family);

// Gives a rig whose joints carry no H-Anim names (a glTF or other skin) the H-Anim names the engine's limbs, walk
// generator and retargeting look for: by the joints' own names where they are a known family's (a Mixamo or
// HumanIK rig), else by the skeleton's shape. The names given: HumanoidRoot or sacroiliac, vl5, vt6, vc4,
// skullbase, and per side sternoclavicular, shoulder, elbow, wrist, hip, knee, ankle, midtarsal. joint_names
// change, source_joint_names keep the file's names, and a warning lists the map and how it was found. Returns false
// (and leaves the skeleton as it was) when the skeleton already has H-Anim limb names or neither its names nor its
// shape are a humanoid's; `why` then says which.
bool name_humanoid_joints(Skeleton& skeleton, std::string* why = nullptr);

}  // namespace strata
