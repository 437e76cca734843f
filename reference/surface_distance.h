#pragma once
// How far one surface lies from another: for `strata report subdiv` (the refined cage against the directly skinned
// level-0 mesh) and anything else that compares two meshes. Measurement code, kept in the library rather than in the
// command so it runs optimised in every build (the sanitizer build compiles the command's files at -O0, where
// this search took 70 s of one test).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

namespace strata {

struct Deviation {
  double max_m = 0.0, mean_m = 0.0;
};

// For every vertex of the first mesh (SoA: x, y, z rows `mesh_stride` apart), the distance to the nearest point of
// the second surface's triangles (SoA likewise, `refined_triangles` indexing it); the max and mean of those.
Deviation surface_deviation(const std::vector<float>& mesh_soa, std::size_t mesh_vertices, std::size_t mesh_stride,
                            const std::vector<float>& refined_soa, std::size_t refined_vertices,
                            std::size_t refined_stride, std::span<const std::uint32_t> refined_triangles);

}  // namespace strata
