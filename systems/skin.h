#pragma once
// Skin system: deforms every walker's body (one resolution level) by linear blend skinning, the paper's
// equation (4), and places it in the world. Output is walker-major, ready for the renderer.
//
// Each walker goes through the vectorised kernel over the level's SkinLayout (systems/skin_kernel.h), walkers
// in parallel. Determinism: every walker's output depends only on its own inputs, so any thread count gives
// the same bytes.
#include <vector>

#include <glm/vec3.hpp>

#include "components/body.h"
#include "components/skin_layout.h"
#include "components/walker.h"

namespace strata {

struct SkinnedCrowd {
  std::size_t vertex_count = 0;     // per walker
  std::vector<glm::vec3> positions;  // world space, layout order; walker w's vertex v at [w * vertex_count + v]
  std::vector<glm::vec3> normals;
};

void skin_system(const SkinLayout& layout, const WalkerLanes& lanes, SkinnedCrowd& out);

}  // namespace strata
