#pragma once
// SubdivSurface: what the per-frame subdivision path (systems/subdiv.h) needs to turn a skinned cage into the
// refined surface, built once per rig and level from the bound cage (immutable rig data, shared by every walker).
//
// Refinement is linear in the cage: every refined vertex is a fixed weighted sum of cage vertices. OpenSubdiv
// computes the weights once (a Far::TopologyRefiner refined uniformly); each frame only the sums remain. They are
// stored LEVEL BY LEVEL: steps[k] makes level k + 1 from level k. The alternative, OpenSubdiv's factorised
// stencil table (every level-L vertex directly from the cage), needs more terms per refined vertex as L grows
// (default cage: 4.7 / 8.2 / 10.3 at levels 1 / 2 / 3, against 4.7 / 5.9 / 6.2 counting every level's rows level
// by level, since three quarters of each new level are 4-term edge points), and measured ~1.5x slower per frame
// at levels 2-3. `strata report subdiv` times both forms and Far::StencilTable::UpdateValues side by side.
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/vec2.hpp>

#include "components/body.h"
#include "components/skin_layout.h"

namespace strata {

// One sparse linear map (CSR): destination row i = sum over k in [offsets[i], offsets[i + 1]) of
// weights[k] * source[indices[k]].
struct SubdivStencils {
  std::uint32_t source_count = 0;
  std::vector<std::uint32_t> offsets;  // rows + 1 entries
  std::vector<std::uint32_t> indices;
  std::vector<float> weights;

  std::size_t rows() const { return offsets.empty() ? 0 : offsets.size() - 1; }
  std::size_t terms() const { return indices.size(); }
};

enum class StencilForm {
  LevelByLevel,  // steps[k]: level k -> k + 1 (the per-frame default)
  Factorised,    // one step: cage -> level L (OpenSubdiv's StencilTableFactory with no intermediate levels)
};

struct SubdivSurface {
  int depth = 0;                       // refinement level L (1..3)
  SkinLayout cage_layout;              // the bound cage grouped for the skinning kernel
  std::vector<SubdivStencils> steps;   // steps.front() reads the cage in cage_layout order
  std::uint32_t vertex_count = 0;      // refined vertices, numbered in the order the triangles first use them
  std::vector<std::uint32_t> opensubdiv_vertex;  // refined vertex -> its index in OpenSubdiv's level-L numbering
  std::vector<std::uint32_t> triangles;  // refined triangles, counter-clockwise from outside like the cage's
  // Face-varying UVs refined once (UVs do not deform); empty when the cage has none. uv_triangles holds 3 indices
  // per triangle into uvs, parallel to `triangles` (a seam gives one vertex several UV values).
  std::vector<glm::vec2> uvs;
  std::vector<std::uint32_t> uv_triangles;

  std::size_t triangle_count() const { return triangles.size() / 3; }
  std::size_t stencil_terms() const {
    std::size_t n = 0;
    for (const SubdivStencils& s : steps) n += s.terms();
    return n;
  }
};

// Refines `cage` (its mesh, and its binding for the layout) `depth` times (1..3) with the options of
// make_cage_refiner (rig/subdiv_refiner.h). Throws std::invalid_argument on a depth outside 1..3, an empty cage
// or a binding whose size does not match the mesh.
SubdivSurface make_subdiv_surface(const BodyLevel& cage, int depth, StencilForm form = StencilForm::LevelByLevel);

// The surface of `body`'s cage at `depth`, built on first use and then kept in the body (Body::subdiv), so every
// scene and walker of the rig shares one copy. nullptr when the body has no cage.
std::shared_ptr<const SubdivSurface> body_subdiv_surface(const Body& body, int depth);

}  // namespace strata
