#pragma once
// Skin system: deforms every walker's body (one resolution level) by linear blend skinning, the paper's
// equation (4), or by dual quaternions or centres of rotation (SkinningMode), and places it in the world. Output is walker-major, ready for the renderer.
//
// Each walker goes through the vectorised kernel over the level's SkinLayout (systems/skin_kernel.h), walkers
// in parallel. Determinism: every walker's output depends only on its own inputs, so any thread count gives
// the same bytes.
//
//   reads:  layout (rest mesh of one level, groups, weights), skinning (joints*12), placement (5),
//           muscle_force (P, optional), the walker rows to skin (optional)
//   writes: the SkinnedCrowd's six vertex arrays (prepared beforehand: SkinnedCrowd::prepare)
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "components/body.h"
#include "components/skin_layout.h"
#include "ecs/aligned_buffer.h"
#include "ecs/column_view.h"
#include "systems/job.h"
#include "systems/skin_kernel.h"

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
  // Sizes the crowd for `walkers` blocks of `vertex_count` vertices (stride = pad_to_lanes(vertex_count)) and
  // records which walker rows they hold (null: block w is walker w). Buffers grow, never shrink: a crowd whose
  // visible count changes every frame must not reallocate every frame. The jobs only write into what this made.
  void prepare(std::size_t vertex_count, std::size_t walkers, const std::vector<std::uint32_t>* walker_ids = nullptr);
  // Block w's six arrays.
  SkinOutput block(std::size_t w) {
    const std::size_t o = w * stride;
    return {px.data() + o, py.data() + o, pz.data() + o, nx.data() + o, ny.data() + o, nz.data() + o, stride};
  }
};

struct SkinJob {
  const SkinLayout* layout = nullptr;
  ColumnView<const float> skinning;      // S(j) per joint, 3x4 column-major (component j*12 + k)
  ColumnView<const float> placement;     // position x, y, z, heading, scale (components/walker.h)
  ColumnView<const float> muscle_force;  // force factor per control point, or empty: no displacement
  // Rows to skin, in the order their blocks are written (culling, per-walker levels); null: every row.
  const std::vector<std::uint32_t>* walkers = nullptr;
  SkinnedCrowd* out = nullptr;           // prepared for this layout and these walkers
  SkinningMode mode = SkinningMode::Linear;  // CentresOfRotation needs the layout's centres

  // The columns (skin_columns_valid), layout and mode (skin_mode_fits) fit; every listed row in range; `out` prepared: its vertex
  // count and stride the layout's, one block per walker skinned, buffers that hold them, walker_ids as listed.
  bool validate() const;
  bool run() const;  // walkers in parallel, four per task
};

// A job over the walker table `walkers` that skins `subset` (null: all) into `out`, which it prepares (the only
// allocation, and only when the crowd grew).
SkinJob make_skin_job(const SkinLayout& layout, const SoaTable& walkers, SkinnedCrowd& out,
                      const std::vector<std::uint32_t>* subset = nullptr, SkinningMode mode = SkinningMode::Linear);

}  // namespace strata
