#pragma once
// SkinLayout: a body level rearranged for the skinning kernel. Vertices are grouped by influence set (the same
// joints, in the same order), so within a group the joint matrices are broadcast once instead of gathered per
// vertex, and everything per vertex (rest position, normal, weights) sits in 64-byte-aligned SoA arrays the
// compiler vectorises over. Built once per level (immutable rig data); output vertices come out in layout order,
// so the layout carries the triangle list renumbered to that order.
#include <array>
#include <cstdint>
#include <vector>

#include "components/body.h"
#include "ecs/aligned_buffer.h"

namespace strata {

struct SkinGroup {
  std::array<std::int16_t, kMaxInfluences> joints{};  // the group's influence set
  std::uint32_t influences = 0;                       // 1..4 joints used
  std::uint32_t first = 0, count = 0;                 // vertex range in layout order
};

struct SkinLayout {
  std::uint32_t vertex_count = 0;
  std::vector<SkinGroup> groups;
  // SoA, layout order, each padded to whole SIMD vectors.
  AlignedBuffer<float> px, py, pz, nx, ny, nz;
  std::array<AlignedBuffer<float>, kMaxInfluences> weight;  // weight[k][v] belongs to groups[g].joints[k]
  std::vector<std::uint32_t> original;                      // layout vertex -> mesh vertex
  std::vector<std::uint32_t> triangles;                     // the mesh's triangles in layout numbering
};

// Groups by influence set (weights renormalised to sum 1; zero-weight slots dropped). Deterministic.
SkinLayout make_skin_layout(const BodyLevel& level);

}  // namespace strata
