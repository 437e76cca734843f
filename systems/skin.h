#pragma once
// Skin system: deforms every walker's body (one resolution level) by linear blend skinning, the paper's
// equation (4), and places it in the world. Output is walker-major, ready for the renderer.
//
// Each walker goes through the vectorised kernel over the level's SkinLayout (systems/skin_kernel.h), walkers
// in parallel. Determinism: every walker's output depends only on its own inputs, so any thread count gives
// the same bytes.
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "components/body.h"
#include "components/skin_layout.h"
#include "ecs/aligned_buffer.h"
#include "components/walker.h"

namespace strata {

// Deformed bodies, SoA: component arrays px .. nz, each walker's block of vertex_count values starting at
// w * stride (stride = vertex_count padded to the SIMD width, so every block is 64-byte aligned). The renderer
// reads these arrays as they are; an interleaved copy would double the pass's memory traffic.
struct SkinnedCrowd {
  std::size_t vertex_count = 0;  // per walker, layout order
  std::size_t stride = 0;
  std::size_t walkers = 0;
  AlignedBuffer<float> px, py, pz, nx, ny, nz;
  // Which walker (row of the walker table) each block belongs to, when only some walkers were skinned (culling,
  // per-walker levels); empty when block w is walker w.
  std::vector<std::uint32_t> walker_ids;

  glm::vec3 position(std::size_t walker, std::size_t v) const {
    const std::size_t i = walker * stride + v;
    return {px[i], py[i], pz[i]};
  }
  glm::vec3 normal(std::size_t walker, std::size_t v) const {
    const std::size_t i = walker * stride + v;
    return {nx[i], ny[i], nz[i]};
  }
  // Axis-aligned bounds of every vertex of every walker; false when empty.
  bool bounds(glm::vec3& lo, glm::vec3& hi) const;
};

// Skins every walker, or only `walkers` when given (rows of the walker table, in the order their blocks are
// written; out.walker_ids records them).
void skin_system(const SkinLayout& layout, const WalkerLanes& lanes, SkinnedCrowd& out,
                 const std::vector<std::uint32_t>* walkers = nullptr);

}  // namespace strata
