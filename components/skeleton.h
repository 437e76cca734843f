#pragma once
// Skeleton: the immutable, shared rig data of one H-Anim humanoid (names, hierarchy, rest centres, limits,
// segments, sites and the optional X3D skin). Loaded once (io/hanim_loader.h) and referenced by every walker of
// that body through a Rig; per-frame systems only read it.
//
// Conventions (H-Anim 1.1 / ISO 19774): metres, right-handed, +Y up, the humanoid faces +Z, +X is its left.
// Every joint's rest rotation is identity and `centers` are absolute rest positions in humanoid coordinates,
// so the rest global frame of joint j is a pure translation by centers[j] (the paper's A(j)).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

namespace strata {

// Which generation of joint names a file used. Both map to one internal set (H-Anim 1.1 names).
enum class JointNaming : std::uint8_t { HAnim1_1, HAnim2019, Mixed };
const char* to_string(JointNaming naming);

// Rotation limits of one joint, radians, about the joint's local x, y, z axes (H-Anim llimit/ulimit; the paper's
// limitx/limity/limitz); `present` is false when the file gave none (then every axis spans [-pi, pi]).
// Three per-axis ranges only mean something with an Euler order. Strata's: R = Rx(x) * Rz(z) * Ry(y) (column
// vectors; intrinsic x, then z, then y), taking the solution with |z| <= pi/2. For a hanging limb that reads as
// flexion (x) of the abducted (z) and twisted (y) bone, so the gimbal lock sits at 90 deg abduction, outside every
// hip's range, rather than at 90 deg flexion, which sitting and reaching forward hit. See components/euler.h.
struct JointLimits {
  glm::vec3 lower{-3.14159265f};
  glm::vec3 upper{3.14159265f};
  bool present = false;
};

struct SkeletonSegment {
  std::string name;
  std::int32_t joint = -1;          // the joint this segment hangs from
  float mass = 0.0f;                // kg, 0 when unknown
  glm::vec3 center_of_mass{0.0f};   // humanoid coordinates at rest
};

// An end effector or landmark (H-Anim Site), e.g. l_forefoot_tip, skull_tip.
struct SkeletonSite {
  std::string name;
  std::int32_t joint = -1;          // the joint that carries it
  glm::vec3 position{0.0f};         // absolute humanoid coordinates at rest
};

// One (vertex, weight) pair of a joint's skinCoordIndex/skinCoordWeight lists.
struct SkinInfluence {
  std::uint32_t vertex = 0;
  float weight = 0.0f;
};

struct Skeleton {
  std::string name;                          // humanoid name
  std::string source;                        // file it came from ("<embedded>/..." for shipped data)
  JointNaming naming = JointNaming::HAnim1_1;

  // Joints in topological order: parents[j] < j for every joint but the root (index 0, parent -1).
  std::vector<std::string> joint_names;         // internal names (H-Anim 1.1 vocabulary where a mapping exists)
  std::vector<std::string> source_joint_names;  // as written in the file
  std::vector<std::int32_t> parents;
  std::vector<glm::vec3> centers;               // absolute rest centres (m)
  std::vector<JointLimits> limits;
  std::vector<glm::vec3> stiffness;             // H-Anim IK hint per axis, 0..1 (default 1 1 1)

  std::vector<SkeletonSegment> segments;
  std::vector<SkeletonSite> sites;

  // Optional X3D skin: rest points in humanoid coordinates, triangles (fans of the IndexedFaceSet polygons),
  // and per-joint influences in CSR form: joint j moves skin_influences[skin_offsets[j] .. skin_offsets[j+1]).
  // skin_offsets is empty when the file had no skin weights, else joint_count() + 1 long.
  std::vector<glm::vec3> skin_points;
  std::vector<std::uint32_t> skin_triangles;
  std::vector<std::uint32_t> skin_offsets;
  std::vector<SkinInfluence> skin_influences;

  // Non-fatal findings of the loader (e.g. a length mismatch that was truncated), "file:line: message".
  std::vector<std::string> warnings;

  std::size_t joint_count() const { return joint_names.size(); }
  // Index of a joint by internal or source name (either naming generation); -1 when absent.
  std::int32_t find_joint(std::string_view name) const;
  // Index of a site by name; -1 when absent.
  std::int32_t find_site(std::string_view name) const;
  // Children count etc. are derived; depth of joint j (root = 0).
  int depth(std::int32_t joint) const;
};

// Maps an H-Anim 2019 joint name to its H-Anim 1.1 equivalent (e.g. "humanoid_root" -> "HumanoidRoot",
// "l_talocrural" -> "l_ankle", "l_radiocarpal" -> "l_wrist"); names without a mapping come back unchanged.
std::string_view canonical_joint_name(std::string_view name);
// True if `name` is a 2019-only joint name (one that canonical_joint_name changes, or a 2019 hand/foot name).
bool is_hanim2019_name(std::string_view name);
// True if `name` is a joint name of H-Anim 1.1 (LOA 4) or of ISO 19774 2019, e.g. "l_hip", "vt12", "humanoid_root",
// "l_tarsometatarsal_2". Used to read a joint's name off its DEF when the file gives none.
bool is_hanim_joint_name(std::string_view name);

// The figure's rest height in metres and what it was measured on: the skin's extent when the skeleton has one,
// else from the lowest joint or site to the skull_tip site, else to the top joint plus 0.13 m (the head above
// skullbase, anthropometry.md). `source` says which ("skin", "skull_tip", "joints").
struct RestStature {
  float metres = 0.0f;
  const char* source = "joints";
};
RestStature rest_stature(const Skeleton& skeleton);

}  // namespace strata
