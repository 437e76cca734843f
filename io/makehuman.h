#pragma once
// Importing the MakeHuman hm08 base mesh (CC0) as an H-Anim body: base.obj (skin group "body" only),
// default.mhskel (163 bones, joints as vertex lists) and default_weights.mhw (per-bone vertex weights), from one
// directory. Errors throw LoadError naming the file; nothing half-loaded is returned.
//
// What comes back (see ImportedBody in io/obj.h):
//   * skeleton: the paper's 25-joint H-Anim set (names, hierarchy and limits of the shipped default skeleton)
//     with centres taken from MakeHuman joints by makehuman_joint_source();
//   * mesh: the "body" group in metres (the file is in decimetres), shifted so the soles touch y = 0, split into
//     the paper's 53 parts by each vertex's strongest MakeHuman bone (makehuman_bone_part());
//   * skin: MakeHuman weights normalised per vertex, folded onto H-Anim joints (makehuman_bone_joint()), top 4,
//     renormalised.
//
// Rest pose: the mesh keeps MakeHuman's A-pose (arms ~45 deg out), and the skeleton's rest is that A-pose.
// H-Anim needs identity rest rotations and absolute centres, not arms at the sides, so the A-pose is a valid
// H-Anim rest. The alternative, re-posing the mesh to arms-down by linear blend skinning, was rejected: LBS
// collapses volume at the shoulder and armpit when it rotates the arm ~45 deg, and that damage would be baked
// into the rest mesh for good, under every later pose. The cost of keeping the A-pose: a clip authored for an
// arms-down rest (and the default shoulder limits) reads ~45 deg off at the shoulders; retargeting a clip onto
// this body must fold in that rest difference.
#include <filesystem>
#include <string_view>

#include "io/obj.h"

namespace strata {

ImportedBody load_makehuman(const std::filesystem::path& dir);
// The same from the three files' contents in memory; `dir_name` stands for the directory in error messages (each
// names "<dir_name>/base.obj", "<dir_name>/default.mhskel" or "<dir_name>/default_weights.mhw").
ImportedBody load_makehuman_text(std::string_view base_obj, std::string_view mhskel, std::string_view mhw,
                                 std::string_view dir_name);

// The documented maps, exposed so tests and tools can check their coverage. Each returns an empty view for a
// bone it does not know.
//   makehuman_bone_part:  MakeHuman bone -> one of paper_part_names() (e.g. "upperarm02.L" -> "lShldr",
//                         "finger1-2.R" -> "rThumb2", face bones -> "head");
//   makehuman_bone_joint: MakeHuman bone -> the H-Anim joint whose rotation moves that bone's skin
//                         (e.g. "lowerarm01.L" -> "l_elbow", "toe3-2.L" -> "l_midtarsal").
std::string_view makehuman_bone_part(std::string_view bone);
std::string_view makehuman_bone_joint(std::string_view bone);
// H-Anim joint -> the MakeHuman joint (a "<bone>____head|tail" key of default.mhskel) that gives its centre;
// HumanoidRoot has none (it is the midpoint of the two hip joints) and gives an empty view.
std::string_view makehuman_joint_source(std::string_view hanim_joint);

}  // namespace strata
