#include "systems/fk.h"

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "ecs/aligned_buffer.h"

namespace strata {
namespace {

// One 3x4 affine matrix per lane, addressed through 12 component pointers (column-major, see walker.h).
struct AffineLanes {
  float* m[kAffineFloats];
};

AffineLanes joint_matrix(float* base, std::size_t stride, std::size_t joint) {
  AffineLanes out;
  for (std::uint32_t k = 0; k < kAffineFloats; ++k) out.m[k] = base + (joint * kAffineFloats + k) * stride;
  return out;
}

}  // namespace

void fk_range(const Skeleton& skeleton, const WalkerLanes& lanes, std::size_t first, std::size_t last) {
  const std::size_t stride = lanes.stride;
  const std::size_t joints = skeleton.joint_count();
  // The chain is accumulated on the skinning matrices G(j) = F(j) A(j)^-1 = G(p) T(c) R T(-c), whose translation
  // is g = G(p).M (c - R c) + g(p). At rest R = I makes c - R c exactly zero, so the rest pose yields exactly the
  // identity. Accumulating F(j) first and subtracting M c afterwards (the textbook order) leaves float residue
  // of ~1e-8 m in every rest skinning matrix; F(j) is then derived as f = M c + g.
  for (std::size_t j = 0; j < joints; ++j) {
    const float* __restrict qx = lanes.local_rotation + (j * 4 + 0) * stride;
    const float* __restrict qy = lanes.local_rotation + (j * 4 + 1) * stride;
    const float* __restrict qz = lanes.local_rotation + (j * 4 + 2) * stride;
    const float* __restrict qw = lanes.local_rotation + (j * 4 + 3) * stride;
    AffineLanes world = joint_matrix(lanes.world, stride, j);
    AffineLanes skin = joint_matrix(lanes.skinning, stride, j);
    const int parent = skeleton.parents[j];
    const float cx = skeleton.centers[j].x, cy = skeleton.centers[j].y, cz = skeleton.centers[j].z;
    // The root's parent frame is the humanoid origin moved by the walker's root translation.
    const float* rt[3] = {lanes.root_translation, lanes.root_translation + stride, lanes.root_translation + 2 * stride};
    AffineLanes p = parent < 0 ? AffineLanes{} : joint_matrix(lanes.skinning, stride, static_cast<std::size_t>(parent));

    for (std::size_t i = first; i < last; ++i) {
      const float x = qx[i], y = qy[i], z = qz[i], w = qw[i];
      const float n = x * x + y * y + z * z + w * w;
      const float s = n > 0.0f ? 2.0f / n : 0.0f;
      // Local rotation R, column-major r0..r8.
      const float r0 = 1.0f - s * (y * y + z * z), r1 = s * (x * y + w * z), r2 = s * (x * z - w * y);
      const float r3 = s * (x * y - w * z), r4 = 1.0f - s * (x * x + z * z), r5 = s * (y * z + w * x);
      const float r6 = s * (x * z + w * y), r7 = s * (y * z - w * x), r8 = 1.0f - s * (x * x + y * y);
      // d = c - R c: how far the rotation about the joint centre moves the origin.
      const float dx = cx - (r0 * cx + r3 * cy + r6 * cz);
      const float dy = cy - (r1 * cx + r4 * cy + r7 * cz);
      const float dz = cz - (r2 * cx + r5 * cy + r8 * cz);
      float m0, m1, m2, m3, m4, m5, m6, m7, m8, gx, gy, gz;
      if (parent < 0) {
        m0 = r0, m1 = r1, m2 = r2, m3 = r3, m4 = r4, m5 = r5, m6 = r6, m7 = r7, m8 = r8;
        gx = dx + rt[0][i], gy = dy + rt[1][i], gz = dz + rt[2][i];
      } else {
        const float p0 = p.m[0][i], p1 = p.m[1][i], p2 = p.m[2][i];
        const float p3 = p.m[3][i], p4 = p.m[4][i], p5 = p.m[5][i];
        const float p6 = p.m[6][i], p7 = p.m[7][i], p8 = p.m[8][i];
        m0 = p0 * r0 + p3 * r1 + p6 * r2;
        m1 = p1 * r0 + p4 * r1 + p7 * r2;
        m2 = p2 * r0 + p5 * r1 + p8 * r2;
        m3 = p0 * r3 + p3 * r4 + p6 * r5;
        m4 = p1 * r3 + p4 * r4 + p7 * r5;
        m5 = p2 * r3 + p5 * r4 + p8 * r5;
        m6 = p0 * r6 + p3 * r7 + p6 * r8;
        m7 = p1 * r6 + p4 * r7 + p7 * r8;
        m8 = p2 * r6 + p5 * r7 + p8 * r8;
        gx = p0 * dx + p3 * dy + p6 * dz + p.m[9][i];
        gy = p1 * dx + p4 * dy + p7 * dz + p.m[10][i];
        gz = p2 * dx + p5 * dy + p8 * dz + p.m[11][i];
      }
      skin.m[0][i] = m0, skin.m[1][i] = m1, skin.m[2][i] = m2;
      skin.m[3][i] = m3, skin.m[4][i] = m4, skin.m[5][i] = m5;
      skin.m[6][i] = m6, skin.m[7][i] = m7, skin.m[8][i] = m8;
      skin.m[9][i] = gx, skin.m[10][i] = gy, skin.m[11][i] = gz;
      // F(j) = G(j) T(c): same rotation, translation M c + g (the joint centre, posed).
      world.m[0][i] = m0, world.m[1][i] = m1, world.m[2][i] = m2;
      world.m[3][i] = m3, world.m[4][i] = m4, world.m[5][i] = m5;
      world.m[6][i] = m6, world.m[7][i] = m7, world.m[8][i] = m8;
      world.m[9][i] = m0 * cx + m3 * cy + m6 * cz + gx;
      world.m[10][i] = m1 * cx + m4 * cy + m7 * cz + gy;
      world.m[11][i] = m2 * cx + m5 * cy + m8 * cz + gz;
    }
  }
}

void fk_system(const Skeleton& skeleton, const WalkerLanes& lanes) {
  if (lanes.count == 0) return;
  // 256 walkers per task: a 25-joint chunk touches ~60 KiB per matrix field, small enough to stay in L2 while
  // the joint loop revisits parents, large enough that task overhead is noise.
  constexpr std::size_t kChunk = 256;
  if (lanes.count <= kChunk) {
    fk_range(skeleton, lanes, 0, lanes.count);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lanes.count, kChunk),
                    [&](const tbb::blocked_range<std::size_t>& r) { fk_range(skeleton, lanes, r.begin(), r.end()); },
                    tbb::simple_partitioner());
}

}  // namespace strata
