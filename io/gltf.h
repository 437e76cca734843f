#pragma once
// Importing a skinned glTF 2.0 body (.gltf or .glb, via tinygltf) as an H-Anim-style ImportedBody (io/obj.h).
// Errors throw LoadError "FILE: <what>: reason" naming the accessor or node index at fault; nothing
// half-loaded is returned.
//
// What is read: the first node (depth-first through the default scene) that has both a mesh and a skin; every
// triangle primitive of that mesh with POSITION, JOINTS_0 and WEIGHTS_0 (NORMAL and TEXCOORD_0 when all such
// primitives have them; indices u8/u16/u32), concatenated in order, one part per primitive; the skin's joints and
// inverse bind matrices; the default-pose node transforms; and the first animation.
//
// What comes back, with N_k the global matrix of skin joint k's node and IBM_k its inverse bind matrix:
//   * skeleton: one joint per skin joint (a synthetic "skin_root" at the origin above them when the skin has
//     several roots), parents from the node tree restricted to skin joints, parents first; names from the nodes
//     or "joint_<k>"; centres c = the joints' positions at the default pose, in scene space;
//   * mesh: the vertices skinned at the default pose, v = sum_i w_i N_ki IBM_ki v_bind, so the scene's root
//     transforms (e.g. a Z-up -> Y-up root matrix) are applied and the result is in H-Anim's Y-up space; vertex
//     order is the primitives' own order;
//   * skin: JOINTS_0/WEIGHTS_0 mapped to skeleton indices, normalised to sum 1 (some exporters write sums below
//     1), zero-weight slots joint 0;
//   * clips[0]: the animation baked at the union of its key times. At time t, skin joint k's skinning matrix
//     relative to the rest mesh is S_k(t) = N_k(t) IBM_k (N_k^default IBM_k)^-1 = N_k(t) (N_k^default)^-1,
//     identity at the default pose. H-Anim's chain G_j = G_parent T(c_j) R_j T(-c_j) is then solved per joint:
//     R_j = rotation part of G_parent^-1 S_j (root: G_root = T(root translation) T(c) R T(-c), exact). This is
//     exact where the joint only rotates about its own default position; animated translation or scale of a
//     non-root joint cannot be expressed by a rotation about c_j and is lost. The largest such residual over all
//     keys and joints is reported in ImportedBody::warnings. Between keys, Strata slerps the baked global-frame
//     rotations, which differs slightly from slerping the glTF's local ones.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>

#include "io/obj.h"

namespace strata {

ImportedBody load_gltf(const std::filesystem::path& path);
// The same from bytes in memory (a GLB, or glTF JSON whose buffers are embedded as data: URIs; external files are
// refused, since there is no directory to resolve them against). `source_name` is used in error messages and
// names the skeleton.
ImportedBody load_gltf_memory(std::span<const std::uint8_t> bytes, std::string_view source_name);

}  // namespace strata
