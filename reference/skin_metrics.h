#pragma once
// Skin quality metrics for `strata report skin`: what linear blend skinning gets wrong, measured on a posed mesh
// against its rest mesh. All inputs are humanoid space (metres).
#include <cstddef>
#include <span>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "components/mesh.h"
#include "components/skeleton.h"
#include "components/skin_layout.h"

namespace strata {

struct SkinMetricsOptions {
  // A triangle whose posed area falls below this fraction of its rest area counts as inverted: a collapsed
  // triangle has no reliable normal, and visually it is the same candy-wrapper failure.
  double collapse_fraction = 0.05;
  // Rest vertices closer than this are one point split in the index buffer (a UV or normal seam).
  double coincident_m = 1e-6;
};

struct SkinMetrics {
  std::size_t triangles = 0;            // non-degenerate rest triangles examined
  std::size_t inverted_triangles = 0;   // flipped against the carried rest normal, or collapsed
  double seam_gap_max_m = 0.0;          // largest posed distance between rest-coincident vertices
  std::size_t nan_count = 0;            // posed vertices with a non-finite coordinate
};

// `skinning` are the matrices the pose used (one per joint): a triangle's rest normal is carried by the mean of
// its vertices' weight-blended 3x3s, so a triangle that merely turns with its limb is not flagged, only one that
// turned against its own vertices' motion. `posed` holds one position per rest vertex.
SkinMetrics measure_skin(const Mesh& rest, const SkinBinding& binding, std::span<const glm::mat4> skinning,
                         std::span<const glm::vec3> posed, const SkinMetricsOptions& options = {});

// Signed volume enclosed between `centre` and the triangles of `mesh` (indices; `positions` are the coordinates to
// use, rest or posed) whose centroid lies within `radius` of `centre`: sum over those triangles of
// dot(a - c, (b - c) x (d - c)) / 6, the divergence theorem with the cone to the centre. For a closed,
// outward-wound surface entirely inside the radius this is its volume; for a limb it is the volume of the
// sleeve around the joint seen from the joint, which is what creases and candy wrappers lose.
double joint_volume(const Mesh& mesh, std::span<const glm::vec3> positions, const glm::vec3& centre, float radius);

// Percentage change of joint_volume from rest to posed, over the same triangles: those selected in the rest mesh
// about rest_centre, evaluated posed about posed_centre (selecting again in the posed mesh would change the
// triangle set with the pose and measure the selection, not the skin).
double joint_volume_change_pct(const Mesh& rest, std::span<const glm::vec3> posed, const glm::vec3& rest_centre,
                               const glm::vec3& posed_centre, float radius);

// The report's elbow/knee number: bends `joint` alone by `angle_rad` about its local x axis in the direction its
// limits allow more of (elbows flex negative, knees positive in H-Anim), skins with the reference skinning and
// returns joint_volume_change_pct about the joint with `radius`.
// In any skinning mode (centres: per mesh vertex, for CentresOfRotation).
double flexion_volume_change_pct(const Mesh& rest, const SkinBinding& binding, const Skeleton& skeleton, int joint,
                                 float angle_rad, float radius, SkinningMode mode = SkinningMode::Linear,
                                 std::span<const glm::vec3> centres = {});

// The pose of that flexion: local rotations with `joint` bent by angle_rad the way its limits allow more of.
std::vector<glm::quat> flexion_rotations(const Skeleton& skeleton, int joint, float angle_rad);

// Bulge: after the flexion of `joint` by angle_rad, the largest amount (m) by which a vertex within `radius` of
// the joint (at rest) lies farther from the posed bones than it lay from the rest bones. The bones are the
// segments parent joint -> joint and joint -> `child`. A vertex that moves rigidly with either bone can only
// come closer to the pair, so what exceeds rest is skin pushed outward (the dual-quaternion bulge).
double flexion_bulge_m(const Mesh& rest, const SkinBinding& binding, const Skeleton& skeleton, int joint, int child,
                       float angle_rad, float radius, SkinningMode mode = SkinningMode::Linear,
                       std::span<const glm::vec3> centres = {});

// Twist: the cross-section area of a limb turned by angle_rad about the axis joint -> child at `joint`, against
// rest. The section is the plane across that axis through the middle of the limb's blend zone (the mean axial
// position of the vertices `joint` shares with its parent, weighted by min(w, 1 - w)), cut through the
// triangles of vertices bound only to `joint` and its parent; its area is that of the closed cut, oriented by
// the posed triangles. 1 = the limb keeps its girth; linear blending's candy wrapper drives it towards 0.
struct TwistSection {
  double area_ratio = 1.0;
  double rest_area_m2 = 0.0, posed_area_m2 = 0.0;
  double axial_m = 0.0;  // where the section lies along the axis from the joint
};
TwistSection twist_section(const Mesh& rest, const SkinBinding& binding, const Skeleton& skeleton, int joint,
                           int child, float angle_rad, SkinningMode mode = SkinningMode::Linear,
                           std::span<const glm::vec3> centres = {});

}  // namespace strata
