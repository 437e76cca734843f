#pragma once
// Writing a skinned H-Anim body as a glTF 2.0 binary (.glb), through tinygltf's writer.
//
// Mapping (../shared/notes/tech-brief.md section 5.2):
//   * one node per joint, named after it (the skeleton's H-Anim 1.1 names), parents first in skeleton order;
//     translation = c_j - c_parent (root: c_root), rotation identity at rest: H-Anim's rest pose is the bind pose;
//   * a skin over those nodes with inverse bind matrices translate(-c_j) (H-Anim rest rotations are identity, so
//     N_j IBM_j = G_j, the skinning matrix of Strata's FK);
//   * the body level's rest mesh as one triangle primitive: POSITION (with min/max), NORMAL (unit), JOINTS_0
//     (unsigned short), WEIGHTS_0 (float, each row summing to 1, zero-weight slots joint 0), indices (unsigned
//     short below 65,535 vertices, else unsigned int), a plain skin-tone material; on a node of its own at the
//     scene root (glTF ignores the transform of a skinned mesh's node);
//   * an optional clip as one animation: a LINEAR rotation channel per rotation track (quaternions x, y, z, w)
//     and a LINEAR translation channel per translation track, whose H-Anim value t is written as the root node's
//     translation t + c_root (H-Anim's root translation is an offset of the root's rest position).
// The muscle layer's displacement has no glTF counterpart (it would need per-frame morph targets) and is not
// written.
//
// The file is written to a temporary name beside `path` and renamed over it only when complete, so a failure
// never leaves a half-written file (nor a temporary one).
#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "components/animation_clip.h"
#include "components/body.h"
#include "components/skeleton.h"

namespace strata {

// "FILE: reason", one line.
struct ExportError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct GltfExportStats {
  std::size_t vertices = 0, triangles = 0, joints = 0, keys = 0, bytes = 0;
  // Vertices in the file: `vertices`, plus one per extra texture coordinate a UV seam gives a vertex (a mesh with
  // corner_uvs is split there, glTF's attributes being per vertex).
  std::size_t written_vertices = 0;
};

// Writes `level` (bound to `skeleton`) and, when given, `clip` to `path` as GLB. Throws ExportError naming the
// path when the mesh, binding or clip does not fit the skeleton (vertex and binding counts differ, a joint index
// out of range, a track of an unknown joint, key times not strictly increasing, a non-finite value) or the file
// cannot be written.
GltfExportStats write_gltf_binary(const std::filesystem::path& path, const Skeleton& skeleton, const BodyLevel& level,
                                  const AnimationClip* clip, const std::string& name = "strata_walker");

}  // namespace strata
