#pragma once
// The skeleton pass's geometry, with no GL: the unit meshes it instances (a tapered bone prism and a joint
// sphere) and the per-instance transform that places a bone. Kept apart from the pass so the maths can be tested
// (and read) without a context.
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace strata {

struct MeshVertex {
  glm::vec3 position;
  glm::vec3 normal;
};

// An indexed triangle mesh with 16-bit indices (both unit meshes are far below 65,536 vertices).
struct UnitMesh {
  std::vector<MeshVertex> vertices;
  std::vector<std::uint16_t> indices;
};

// Tapered prism from radius 1 at y = 0 to 0.55 at y = 1 (the taper shows the bone's direction), capped at both
// ends, with smooth side normals.
UnitMesh make_bone_mesh();
// Unit UV sphere, 8 stacks x 12 slices (168 triangles), single pole vertices, smooth normals.
UnitMesh make_sphere_mesh();

// The per-instance transform of one bone: maps the unit bone mesh (radius 1 about the segment (0,0,0)-(0,1,0))
// onto the segment a -> b with the given radius. Columns 0 and 2 are orthogonal to b - a with length `radius`,
// column 1 is b - a, column 3 is a; the determinant is positive so winding (and back-face culling) survives.
// nullopt for a zero-length or non-finite bone, which the renderer skips (its joint sphere still shows).
std::optional<glm::mat4> bone_transform(const glm::vec3& a, const glm::vec3& b, float radius);

}  // namespace strata
