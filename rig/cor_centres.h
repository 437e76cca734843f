#pragma once
// Optimised centres of rotation (Le & Hodgins, "Real-time skeletal skinning with optimized centers of rotation",
// SIGGRAPH 2016): per vertex with two or more influences, a rest-space point about which the blended rotation
// turns it (SkinningMode::CentresOfRotation). The centre is the average of the rest triangles' centroids,
// weighted by triangle area and by how similar the triangle's skin weights are to the vertex's:
//
//   c_v = sum_t sim(w_v, w_t) * area_t * centroid_t / sum_t sim(w_v, w_t) * area_t
//   sim(w_p, w_v) = sum_{j != k} w_pj w_pk w_vj w_vk exp(-(w_pj w_vk - w_pk w_vj)^2 / sigma^2)
//
// with w_t the mean of the triangle's three vertex weights. Immutable rig data: computed once per body level,
// shared by every walker (Body::cor), and cached on disk beside the body cache, keyed by a hash of everything it
// depends on (mesh, triangles, binding, sigma, algorithm version), so an edited binding or mesh recomputes.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "components/body.h"

namespace strata {

struct CorOptions {
  // The similarity's width in weight difference (for two joints, w_pj w_vk - w_pk w_vj is the difference of the
  // two vertices' weights). Le & Hodgins use 0.1, which gives each ring of a blend its own centre. The default
  // body's knee blends over +-8 cm of skin: at 0.1 the rings far from the middle get centres off the joint whose
  // linear blend (the chord) shortens the bent knee (-7.1 % of volume at 120 deg). 0.5 lets a ring's centre lean
  // towards the blend's middle ring, nearer the joint: knee -4.8 %, elbow -3.6 -> -2.6 %, at the cost of more of
  // the outward bulge dual quaternions show (knee 5.5 -> 8.2 mm beyond rest, dual quaternions 10.2; elbow 1.7 ->
  // 3.8, dual quaternions 5.7). Rejected: 0.3 (knee -5.9 %), a narrower knee blend (12 triangles flip behind the
  // knee over the walk), and 1 or more (centres nearly shared: the bulge of dual quaternions, 9.7-10.3 mm).
  double sigma = 0.5;
};

struct CorCentres {
  std::vector<glm::vec3> centres;  // per mesh vertex; a vertex with < 2 influences keeps its rest position
  std::size_t solved = 0;          // vertices with >= 2 influences given a centre from similar triangles
  std::size_t fallback = 0;        // vertices with >= 2 influences and no similar triangle: rest position kept
  double seconds = 0.0;            // the precomputation's wall time (0 when loaded from the disk cache)
  bool from_cache = false;
};

// The exact sum above, accelerated without approximation: sim is zero unless the triangle's weights and the
// vertex's share at least two joints, so triangles are indexed by the joint pairs their weights cover, and each
// influence set (vertices sharing their joints, as the skin layout groups them) visits only the triangles of
// its pairs. Parallel over vertices; the result does not depend on the thread count.
CorCentres compute_cor_centres(const Mesh& mesh, const SkinBinding& binding, const CorOptions& options = {});

// Key of the centres of this mesh and binding (content hash).
std::uint64_t cor_cache_key(const Mesh& mesh, const SkinBinding& binding, const CorOptions& options = {});
// compute_cor_centres through the disk cache (body_cache_directory(); none: no caching): a stored file with
// the same key is loaded, else the centres are computed and stored (atomically; failures are silent).
CorCentres cached_cor_centres(const Mesh& mesh, const SkinBinding& binding, const CorOptions& options = {});
std::optional<std::vector<glm::vec3>> load_cor_cache(const std::filesystem::path& file, std::uint64_t key);
void save_cor_cache(const std::filesystem::path& file, std::uint64_t key, const std::vector<glm::vec3>& centres);

// The centres of body level `level` (0..2), or of the cage (level -1), computed (through the disk cache) on the
// first request and then shared (Body::cor). Null when the body has no such level.
std::shared_ptr<const CorCentres> body_cor_centres(const Body& body, int level);

}  // namespace strata
