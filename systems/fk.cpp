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
  for (std::size_t j = 0; j < joints; ++j) {
    const float* __restrict qx = lanes.local_rotation + (j * 4 + 0) * stride;
    const float* __restrict qy = lanes.local_rotation + (j * 4 + 1) * stride;
    const float* __restrict qz = lanes.local_rotation + (j * 4 + 2) * stride;
    const float* __restrict qw = lanes.local_rotation + (j * 4 + 3) * stride;
    AffineLanes out = joint_matrix(lanes.world, stride, j);
    AffineLanes skin = joint_matrix(lanes.skinning, stride, j);
    const int parent = skeleton.parents[j];
    const glm::vec3 c = skeleton.centers[j];
    // The offset from the parent's centre (the paper's R(j)); the root is offset from the humanoid origin and
    // also carries the per-walker root translation.
    const glm::vec3 offset = parent < 0 ? c : c - skeleton.centers[parent];

    if (parent < 0) {
      const float* __restrict rx = lanes.root_translation + 0 * stride;
      const float* __restrict ry = lanes.root_translation + 1 * stride;
      const float* __restrict rz = lanes.root_translation + 2 * stride;
      for (std::size_t i = first; i < last; ++i) {
        const float x = qx[i], y = qy[i], z = qz[i], w = qw[i];
        const float n = x * x + y * y + z * z + w * w;
        const float s = n > 0.0f ? 2.0f / n : 0.0f;
        out.m[0][i] = 1.0f - s * (y * y + z * z);
        out.m[1][i] = s * (x * y + w * z);
        out.m[2][i] = s * (x * z - w * y);
        out.m[3][i] = s * (x * y - w * z);
        out.m[4][i] = 1.0f - s * (x * x + z * z);
        out.m[5][i] = s * (y * z + w * x);
        out.m[6][i] = s * (x * z + w * y);
        out.m[7][i] = s * (y * z - w * x);
        out.m[8][i] = 1.0f - s * (x * x + y * y);
        out.m[9][i] = offset.x + rx[i];
        out.m[10][i] = offset.y + ry[i];
        out.m[11][i] = offset.z + rz[i];
      }
    } else {
      AffineLanes p = joint_matrix(lanes.world, stride, static_cast<std::size_t>(parent));
      for (std::size_t i = first; i < last; ++i) {
        const float x = qx[i], y = qy[i], z = qz[i], w = qw[i];
        const float n = x * x + y * y + z * z + w * w;
        const float s = n > 0.0f ? 2.0f / n : 0.0f;
        // Local rotation R (column-major r0..r8).
        const float r0 = 1.0f - s * (y * y + z * z), r1 = s * (x * y + w * z), r2 = s * (x * z - w * y);
        const float r3 = s * (x * y - w * z), r4 = 1.0f - s * (x * x + z * z), r5 = s * (y * z + w * x);
        const float r6 = s * (x * z + w * y), r7 = s * (y * z - w * x), r8 = 1.0f - s * (x * x + y * y);
        const float p0 = p.m[0][i], p1 = p.m[1][i], p2 = p.m[2][i];
        const float p3 = p.m[3][i], p4 = p.m[4][i], p5 = p.m[5][i];
        const float p6 = p.m[6][i], p7 = p.m[7][i], p8 = p.m[8][i];
        // F(j) = F(p) * [R | offset]: rotation P*R, translation P*offset + t_p.
        out.m[0][i] = p0 * r0 + p3 * r1 + p6 * r2;
        out.m[1][i] = p1 * r0 + p4 * r1 + p7 * r2;
        out.m[2][i] = p2 * r0 + p5 * r1 + p8 * r2;
        out.m[3][i] = p0 * r3 + p3 * r4 + p6 * r5;
        out.m[4][i] = p1 * r3 + p4 * r4 + p7 * r5;
        out.m[5][i] = p2 * r3 + p5 * r4 + p8 * r5;
        out.m[6][i] = p0 * r6 + p3 * r7 + p6 * r8;
        out.m[7][i] = p1 * r6 + p4 * r7 + p7 * r8;
        out.m[8][i] = p2 * r6 + p5 * r7 + p8 * r8;
        out.m[9][i] = p0 * offset.x + p3 * offset.y + p6 * offset.z + p.m[9][i];
        out.m[10][i] = p1 * offset.x + p4 * offset.y + p7 * offset.z + p.m[10][i];
        out.m[11][i] = p2 * offset.x + p5 * offset.y + p8 * offset.z + p.m[11][i];
      }
    }
    // S(j) = F(j) * T(-c): same rotation, translation t - M c.
    for (std::size_t i = first; i < last; ++i) {
      for (std::uint32_t k = 0; k < 9; ++k) skin.m[k][i] = out.m[k][i];
      skin.m[9][i] = out.m[9][i] - (out.m[0][i] * c.x + out.m[3][i] * c.y + out.m[6][i] * c.z);
      skin.m[10][i] = out.m[10][i] - (out.m[1][i] * c.x + out.m[4][i] * c.y + out.m[7][i] * c.z);
      skin.m[11][i] = out.m[11][i] - (out.m[2][i] * c.x + out.m[5][i] * c.y + out.m[8][i] * c.z);
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
