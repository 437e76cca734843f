#pragma once
// Skin system: deforms every walker's body (one resolution level) by linear blend skinning, the paper's
// equation (4), and places it in the world. Output is walker-major, ready for the renderer.
//
// For now each walker goes through the scalar reference kernel (systems/skin_reference.h) in parallel over
// walkers; the SIMD kernel over SoA vertex groups that replaces it is issue 6's. Determinism: every walker's
// output depends only on its own inputs, so any thread count gives the same bytes.
#include <vector>

#include <glm/vec3.hpp>

#include "components/body.h"
#include "components/walker.h"

namespace strata {

struct SkinnedCrowd {
  std::size_t vertex_count = 0;     // per walker
  std::vector<glm::vec3> positions;  // world space; walker w's vertex v at [w * vertex_count + v]
  std::vector<glm::vec3> normals;
};

void skin_system(const BodyLevel& level, const WalkerLanes& lanes, SkinnedCrowd& out);

}  // namespace strata
