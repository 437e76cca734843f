#pragma once
// The procedural default body: a closed, 2-manifold adult skin (1.75 m) grown around a skeleton's rest joint
// centres and sites, at the paper's three resolution levels plus a low-resolution subdivision cage, each vertex
// tagged with one of the 53 paper parts (paper_part_names()).
//
// Route: a signed-distance body (smoothly blended capsules, round cones and ellipsoids placed from the joint
// centres; the trunk is lofted through the anthropometry slice table), marching tetrahedra over a uniform grid,
// then meshoptimizer simplification to the vertex budgets. Marching tetrahedra rather than marching cubes: the
// tetrahedral isosurface is a 2-manifold by construction, so no ambiguity table and no crack repair is needed.
//
// The body is mirror-symmetric about x = 0: it is modelled from the midline and the LEFT limbs, and the right
// side is the exact mirror (the default skeleton is symmetric to 0.6 cm; its spine's small x drift is ignored).
#include <array>
#include <cstdint>

#include "components/mesh.h"
#include "components/skeleton.h"

namespace strata {

struct BodyOptions {
  // Edge of the extraction grid (m). 3.5 mm keeps fingers apart and gives the finest level enough detail.
  float grid_cell = 0.0035f;
  // Vertex budgets of the three levels (the paper's) and of the cage; each is met to within 1 %.
  std::array<std::uint32_t, 3> level_vertices{17953, 8923, 5133};
  std::uint32_t cage_vertices = 1800;
};

struct BodyLevels {
  std::array<Mesh, 3> levels;  // "default_body_L0" (finest) .. "default_body_L2"
  Mesh cage;                   // "default_body_cage", for OpenSubdiv refinement
};

// Generates the body from `skeleton` (needs the 25 default joints l_/r_ hip, knee, ankle, midtarsal, shoulder,
// elbow, wrist, the spine joints and skullbase; throws std::runtime_error naming a missing one). Deterministic:
// the same input gives bit-identical meshes whatever the thread count.
BodyLevels generate_default_body(const Skeleton& skeleton, const BodyOptions& options = {});

// The default humanoid's body, generated on first use (thread-safe, once per process) and then shared.
const BodyLevels& default_body();

// Signed distance (m, negative inside) of the body's implicit surface at p, for tests and tools.
float body_signed_distance(const Skeleton& skeleton, const glm::vec3& p);

}  // namespace strata
