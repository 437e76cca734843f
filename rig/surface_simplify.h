#pragma once
// Simplifying a closed 2-manifold triangle surface to an exact vertex count, keeping it closed and 2-manifold:
// the route every generated body (rig/body_generator.h, rig/makehuman_body.h) takes from its fine surface to the
// paper's resolution levels and the subdivision cage.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "components/mesh.h"

namespace strata {

struct SimplifiedSurface {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> triangles;
  std::vector<std::uint32_t> source_vertex;  // per vertex, the input vertex it is (a collapse moves none)
};

// Shape quality (twice the area over the longest edge squared, normalised: 1 equilateral, 0 degenerate) that a
// collapse may not push a triangle under, unless it was already lower, for meshes that linear blend skinning
// will deform. Slivers are what it flips first: across a triangle 40 mm long and 1 mm high, a 1 % weight
// difference over a 0.2 m lever turns it over. 0.2 stalled the collapse far above the paper's vertex budgets.
inline constexpr double kSkinnedMinQuality = 0.1;

// Quadric-error half-edge collapse down to exactly `target_vertices` (fewer collapses only when none is left
// that keeps the surface valid), refusing collapses that break the link condition, fold a triangle or leave a
// sliver below `min_quality`. The result is compacted to its vertices and ordered for the post-transform cache
// and fetch locality (meshoptimizer). Deterministic. The input must be a closed 2-manifold (not checked: the
// check costs as much as a level's simplification on the procedural body's million triangles); throws
// std::logic_error if the output is not one.
SimplifiedSurface simplify_surface(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& triangles,
                                   std::uint32_t target_vertices, double min_quality);

// A body level from a simplified surface: the paper's part names (components/mesh.h), each vertex's part from
// part_of(v, position), area-weighted normals. What both shipped bodies make of each level and cage.
Mesh body_level_mesh(SimplifiedSurface surface, std::string name,
                     const std::function<std::uint16_t(std::size_t, const glm::vec3&)>& part_of);

// Every directed edge used once and its reverse once, no degenerate triangle, every vertex's fan one cycle.
bool is_closed_manifold(const std::vector<std::uint32_t>& triangles, std::size_t vertex_count);

}  // namespace strata
