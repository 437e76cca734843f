#pragma once
// The scalar twin of skinning: the paper's equation (4), v' = sum_i w_i F(j_i) A(j_i)^-1 v, one vertex at a time
// in double precision. Slow and obvious; the data-parallel skinning system and the renderer are checked against
// it, and the skin metrics (rig/skin_metrics.h) pose meshes with it.
#include <cstddef>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "components/mesh.h"
#include "components/muscle.h"
#include "components/skin_layout.h"
#include "components/walker.h"

namespace strata {

struct SkinnedVertices {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // unit
};

// Poses `rest` with `binding` and one skinning matrix S_j = F(j) A(j)^-1 per joint. Normals go through the
// weight-blended 3x3 and are renormalised; a blended normal of (near) zero length, which opposing rotations can
// produce, falls back to the rest normal so no NaN leaves. Rest normals are computed from the triangles when the
// mesh has none. Weights are divided by their sum, so a binding whose float weights sum to 1 +- 1e-7 still maps
// the identity pose to the rest mesh bit for bit. Throws std::invalid_argument when the binding's vertex count
// differs from the mesh's or a joint index is outside `skinning`.
SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning);
// The same in any SkinningMode, in double, one vertex at a time: the twin of every kernel mode.
//   DualQuaternion: each S_j's rotation as a unit quaternion (its translation as the dual part), the vertex's
//     dual quaternions aligned in sign with its lowest-numbered joint's, blended, normalised; v' = R v + t,
//     n' = R n.
//   CentresOfRotation: R the normalised sign-aligned blend of the rotations, c the vertex's centre (`centres`,
//     per mesh vertex, rig/cor_centres.h); v' = R (v - c) + sum_i w_i S_j c, n' = R n.
// Vertices with one influence are the rigid S_j v in every mode. Throws std::invalid_argument when
// CentresOfRotation gets no centre per vertex.
SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning,
                               SkinningMode mode, std::span<const glm::vec3> centres = {});
// The same with the skinning matrices of walker `walker` read from its lanes (3x4 column-major, walker.h).
SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, const WalkerLanes& lanes,
                               std::size_t walker);
// Muscle displacement for the reference: d_v = sum_i falloff * w_i * sum_a share_a * magnitude_a * gain * f[p_i],
// evaluated in double straight from the binding (not from the kernel's folded coefficients), added along the
// skinned normal. `force` holds one walker's force factors (systems/muscle.h), humanoid units.
struct MuscleReference {
  const MuscleSet* set = nullptr;
  const MuscleBinding* binding = nullptr;
  MuscleGains gains;
  std::span<const float> force;
};
SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning,
                               const MuscleReference& muscles);
// The same in any SkinningMode (below).
SkinnedVertices skin_reference(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning,
                               SkinningMode mode, std::span<const glm::vec3> centres, const MuscleReference& muscles);
// The muscle displacement of every mesh vertex (0 for unbound ones), humanoid metres.
std::vector<double> muscle_displacement_reference(std::size_t vertex_count, const MuscleReference& muscles);
// The force factors of walker `walker` from its lanes.
std::vector<float> walker_muscle_forces(const WalkerLanes& lanes, std::size_t walker);

// The skinning matrices of one walker as glm matrices (fourth row 0 0 0 1).
std::vector<glm::mat4> walker_skinning_matrices(const WalkerLanes& lanes, std::size_t walker);

}  // namespace strata
