#pragma once
// Skin quality metrics for `strata report skin`: what linear blend skinning gets wrong, measured on a posed mesh
// against its rest mesh. All inputs are humanoid space (metres).
#include <cstddef>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "components/mesh.h"
#include "components/skeleton.h"

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
double flexion_volume_change_pct(const Mesh& rest, const SkinBinding& binding, const Skeleton& skeleton, int joint,
                                 float angle_rad, float radius);

}  // namespace strata
