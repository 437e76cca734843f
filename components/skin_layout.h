#pragma once
// SkinLayout: a body level rearranged for the skinning kernel. Vertices are grouped by influence set (the same
// joints, in the same order), so within a group the joint matrices are broadcast once instead of gathered per
// vertex, and everything per vertex (rest position, normal, weights) sits in 64-byte-aligned SoA arrays the
// compiler vectorises over. Built once per level (immutable rig data); output vertices come out in layout order,
// so the layout carries the triangle list renumbered to that order.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "components/body.h"
#include "components/muscle.h"
#include "ecs/aligned_buffer.h"

namespace strata {

// How a vertex's joint transforms are blended (docs/skin.md compares them):
//   Linear            linear blend skinning, the paper's equation (4): blend the 3x4 matrices. Cheapest; the
//                     blended matrix is not a rotation, so bent joints lose volume and twisted ones pinch (the
//                     candy wrapper).
//   DualQuaternion    Kavan et al. 2007/2008: blend unit dual quaternions (antipodality fixed), normalise. Always a
//                     rigid transform, so no collapse; bends bulge a little outward.
//   CentresOfRotation Le & Hodgins 2016: a per-vertex centre c precomputed from the similarity of weights; the
//                     blended (normalised) quaternion R rotates about it, v' = R(v - c) + LBS(c). No candy wrapper,
//                     no dual-quaternion bulge; needs the centres (SkinLayout::cx..cz).
// One-influence vertices are a rigid transform in every mode, so every mode skins them the linear way.
enum class SkinningMode : std::uint8_t { Linear, DualQuaternion, CentresOfRotation };
inline constexpr std::array<SkinningMode, 3> kSkinningModes{SkinningMode::Linear, SkinningMode::DualQuaternion,
                                                             SkinningMode::CentresOfRotation};
// "lbs", "dqs", "cor": the names of --skinning and of report keys.
const char* skinning_mode_name(SkinningMode mode);
std::optional<SkinningMode> parse_skinning_mode(std::string_view name);

struct SkinGroup {
  std::array<std::int16_t, kMaxInfluences> joints{};  // the group's influence set
  std::uint32_t influences = 0;                       // 1..4 joints used
  bool muscle = false;                                // its vertices are bound to the muscle layer
  std::uint32_t first = 0, count = 0;                 // vertex range in layout order
};

struct SkinLayout {
  std::uint32_t vertex_count = 0;
  std::vector<SkinGroup> groups;
  // SoA, layout order, each padded to whole SIMD vectors.
  AlignedBuffer<float> px, py, pz, nx, ny, nz;
  std::array<AlignedBuffer<float>, kMaxInfluences> weight;  // weight[k][v] belongs to groups[g].joints[k]
  std::vector<std::uint32_t> original;                      // layout vertex -> mesh vertex
  std::vector<std::uint32_t> triangles;                     // the mesh's triangles in layout numbering
  // Muscle layer, for vertices of muscle groups (zero elsewhere): the three control points (set-wide index) and
  // their coefficients (rig/muscle_binding.h muscle_coefficients); displacement = scale * sum_i c_i f[point_i].
  std::array<AlignedBuffer<std::int32_t>, kMusclePointsPerVertex> muscle_point;
  std::array<AlignedBuffer<float>, kMusclePointsPerVertex> muscle_coefficient;
  std::vector<std::uint32_t> muscle_slot;  // layout vertex -> index in the MuscleBinding, or kNoMuscle
  std::uint32_t muscle_points = 0;         // 1 + the largest control point index used (0: none)
  // Centres of rotation (SkinningMode::CentresOfRotation), rest space, layout order; empty until
  // set_cor_centres. Kept out of the linear layouts: level 0's take a precomputation (rig/cor_centres.h).
  AlignedBuffer<float> cx, cy, cz;
  static constexpr std::uint32_t kNoMuscle = 0xffffffffu;
  bool has_muscles() const { return !muscle_slot.empty(); }
  bool has_cor_centres() const { return vertex_count > 0 && cx.size() >= vertex_count; }
};

// Groups by influence set (weights renormalised to sum 1; zero-weight slots dropped), and, when `muscles` is
// given, by whether a vertex is bound to the muscle layer, so the kernel pays for the displacement only where
// there is one. Deterministic. Coefficients start at zero: set them with set_muscle_coefficients.
SkinLayout make_skin_layout(const BodyLevel& level, const MuscleBinding* muscles = nullptr);

// Installs per-binding coefficients (muscle_coefficients(), one per bound vertex of the binding the layout was
// made with). Called at start-up and whenever a force value is edited.
void set_muscle_coefficients(SkinLayout& layout, std::span<const std::array<float, kMusclePointsPerVertex>> c);

// Installs centres of rotation given per mesh vertex (mesh order, as rig/cor_centres.h computes them). Throws
// std::invalid_argument when the count is not the layout's vertex count.
void set_cor_centres(SkinLayout& layout, std::span<const glm::vec3> centres);

}  // namespace strata
