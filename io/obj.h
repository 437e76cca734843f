#pragma once
// Reading Wavefront OBJ meshes (v, vt, vn, f, g, o) into a Mesh, and ImportedBody, the common result of the
// skinned-body importers (io/makehuman.h, io/gltf.h). Errors throw LoadError (io/load_error.h) as
// "FILE:LINE: what: reason"; nothing half-loaded is ever returned.
//
// Reading rules (each one a decision the format leaves open):
//   * Positions are indexed by the OBJ vertex (`v`), so a mesh vertex is an OBJ vertex. A UV seam (one `v` used
//     with two different `vt` values) therefore cannot be represented; rather than split vertices, which would
//     break the vertex numbering that external weight files (MakeHuman's .mhw) index, uvs are stored only when
//     every kept vertex has one consistent value, and otherwise dropped altogether. Normals (`vn`) follow the same
//     rule; when they are dropped or absent, compute_normals() fills them.
//   * Faces with more than three corners become fans around their first corner (OBJ polygons are convex in
//     practice; ear clipping would only matter for concave ones).
//   * `g` and `o` both start a group, which becomes a part. A name seen several times is one part. Only a
//     group's first name is used (`g a b` is group "a"). Faces before any group belong to group "default".
//     Parts are numbered in order of first appearance among the kept groups; a vertex belongs to the part of the
//     first kept face that uses it.
//   * An empty group (a `g` followed by no face before the next) is legal in OBJ files exporters write, so it
//     is an error only when ObjOptions::groups asks for it by name and it has no faces.
//   * Vertices no kept face uses are dropped and the rest renumbered in their file order.
//   * Ignored: vp, l, p, s, mtllib, usemtl and unknown statements; line continuations are not supported.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include <glm/gtc/quaternion.hpp>

#include "components/animation_clip.h"
#include "components/mesh.h"
#include "components/skeleton.h"
#include "io/load_error.h"

namespace strata {

struct ObjOptions {
  std::vector<std::string> groups;  // keep only these groups (exact names); empty keeps every group
  float scale = 1.0f;               // multiplies positions, e.g. 0.1 for decimetres -> metres
};

// What a caller needs to tie a loaded mesh back to the file: data indexed by OBJ vertex (weights, joint
// markers) survives the compaction through these.
struct ObjSource {
  std::vector<std::uint32_t> file_vertex;   // per mesh vertex: its 0-based `v` index in the file
  std::vector<glm::vec3> file_positions;    // every `v` of the file, scaled, whether kept or not
};

// Reads a .obj file. `source`, when given, receives the vertex correspondence.
Mesh load_obj_file(const std::filesystem::path& path, const ObjOptions& options = {}, ObjSource* source = nullptr);
// Reads OBJ text from memory; `source_name` is used in error messages and Mesh::name.
Mesh load_obj_text(std::string_view text, std::string_view source_name, const ObjOptions& options = {},
                   ObjSource* source = nullptr);

// A skinned body from an external asset: its skeleton (H-Anim conventions: identity rest rotations, absolute
// centres), its rest mesh in the same space, the mesh's skin binding onto that skeleton, and any animation
// baked into H-Anim local rotations. mesh, skin and skeleton agree: skin.vertex_count() == mesh.vertex_count()
// and every skin joint index is < skeleton.joint_count().
struct ImportedBody {
  Skeleton skeleton;
  Mesh mesh;
  SkinBinding skin;
  std::vector<AnimationClip> clips;
  std::vector<std::string> warnings;  // non-fatal findings, "file: message"
  // The turn about +Y the loader applied so the figure faces +Z (io/gltf.cpp's face_plus_z); identity when none.
  // The file's own space is facing_turn^-1 applied to what is here.
  glm::quat facing_turn{1.0f, 0.0f, 0.0f, 0.0f};
};

}  // namespace strata
