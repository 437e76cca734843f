#include "systems/fk.h"

#include <algorithm>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "components/walker.h"
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

// One joint over walkers [first, last). Measured with bench/fk_bench.cpp (1,000 walkers x 25 joints, one core
// of the 2-core dev VM, SSE2 build): 56 M joints/s when the root test and a compare sat inside the loop and GCC
// left it scalar; 207 M joints/s vectorised as below. At 10,000 walkers (28 MB of columns) it falls to
// 125 M joints/s: memory bound. kRoot selects the root's parent frame (the humanoid origin moved by
// the walker's root translation) at compile time, so the loop body has no branch and vectorises.
template <bool kRoot>
void fk_joint(const float* const q[4], const float* const parent_or_root[kAffineFloats], glm::vec3 center,
              const AffineLanes& world, const AffineLanes& skin, std::size_t first, std::size_t last) {
  const float cx = center.x, cy = center.y, cz = center.z;
  const float* __restrict qx = q[0];
  const float* __restrict qy = q[1];
  const float* __restrict qz = q[2];
  const float* __restrict qw = q[3];
  // Distinct joints' columns never overlap (they are different components of one field), but the compiler
  // cannot see that through 40 pointers; ivdep says so and lets it vectorise without runtime alias checks.
#if !defined(__clang__)  // clang has no ivdep; its own hint warns at -O1, where it does not vectorise anyway
#pragma GCC ivdep
#endif
  for (std::size_t i = first; i < last; ++i) {
    const float x = qx[i], y = qy[i], z = qz[i], w = qw[i];
    // s = 2/|q|^2 accepts unnormalised quaternions. The 1e-30 keeps the zero quaternion finite (every product
    // below is then 0, giving identity) and changes no |q|^2 above 1e-23. It is an add rather than a max or a
    // compare: under -ftrapping-math GCC will not if-convert a float compare, which stops vectorisation.
    const float s = 2.0f / (x * x + y * y + z * z + w * w + 1e-30f);
    // Local rotation R, column-major r0..r8.
    const float r0 = 1.0f - s * (y * y + z * z), r1 = s * (x * y + w * z), r2 = s * (x * z - w * y);
    const float r3 = s * (x * y - w * z), r4 = 1.0f - s * (x * x + z * z), r5 = s * (y * z + w * x);
    const float r6 = s * (x * z + w * y), r7 = s * (y * z - w * x), r8 = 1.0f - s * (x * x + y * y);
    // d = c - R c: how far the rotation about the joint centre moves the origin.
    const float dx = cx - (r0 * cx + r3 * cy + r6 * cz);
    const float dy = cy - (r1 * cx + r4 * cy + r7 * cz);
    const float dz = cz - (r2 * cx + r5 * cy + r8 * cz);
    float m0, m1, m2, m3, m4, m5, m6, m7, m8, gx, gy, gz;
    if constexpr (kRoot) {
      m0 = r0, m1 = r1, m2 = r2, m3 = r3, m4 = r4, m5 = r5, m6 = r6, m7 = r7, m8 = r8;
      gx = dx + parent_or_root[0][i], gy = dy + parent_or_root[1][i], gz = dz + parent_or_root[2][i];
    } else {
      const float* const* p = parent_or_root;
      const float p0 = p[0][i], p1 = p[1][i], p2 = p[2][i];
      const float p3 = p[3][i], p4 = p[4][i], p5 = p[5][i];
      const float p6 = p[6][i], p7 = p[7][i], p8 = p[8][i];
      m0 = p0 * r0 + p3 * r1 + p6 * r2;
      m1 = p1 * r0 + p4 * r1 + p7 * r2;
      m2 = p2 * r0 + p5 * r1 + p8 * r2;
      m3 = p0 * r3 + p3 * r4 + p6 * r5;
      m4 = p1 * r3 + p4 * r4 + p7 * r5;
      m5 = p2 * r3 + p5 * r4 + p8 * r5;
      m6 = p0 * r6 + p3 * r7 + p6 * r8;
      m7 = p1 * r6 + p4 * r7 + p7 * r8;
      m8 = p2 * r6 + p5 * r7 + p8 * r8;
      gx = p0 * dx + p3 * dy + p6 * dz + p[9][i];
      gy = p1 * dx + p4 * dy + p7 * dz + p[10][i];
      gz = p2 * dx + p5 * dy + p8 * dz + p[11][i];
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

// Walkers [first, last) of a validated job.
void fk_range(const FkJob& job, std::size_t first, std::size_t last) {
  const Skeleton& skeleton = *job.skeleton;
  const std::size_t joints = skeleton.joint_count();
  // The chain is accumulated on the skinning matrices G(j) = F(j) A(j)^-1 = G(p) T(c) R T(-c), whose translation
  // is g = G(p).M (c - R c) + g(p). At rest R = I makes c - R c exactly zero, so the rest pose yields exactly the
  // identity. Accumulating F(j) first and subtracting M c afterwards (the textbook order) leaves float residue
  // of ~1e-8 m in every rest skinning matrix; F(j) is then derived as f = M c + g.
  for (std::size_t j = 0; j < joints; ++j) {
    const float* q[4];
    for (std::uint32_t k = 0; k < 4; ++k) q[k] = job.local_rotation.component(static_cast<std::uint32_t>(j * 4 + k));
    const AffineLanes world = joint_matrix(job.world.base, job.world.stride, j);
    const AffineLanes skin = joint_matrix(job.skinning.base, job.skinning.stride, j);
    const int parent = skeleton.parents[j];
    if (parent < 0) {
      const float* root[kAffineFloats] = {job.root_translation.component(0), job.root_translation.component(1),
                                          job.root_translation.component(2)};
      fk_joint<true>(q, root, skeleton.centers[j], world, skin, first, last);
    } else {
      const AffineLanes p = joint_matrix(job.skinning.base, job.skinning.stride, static_cast<std::size_t>(parent));
      fk_joint<false>(q, p.m, skeleton.centers[j], world, skin, first, last);
    }
  }
}

}  // namespace

bool FkJob::validate() const {
  if (!skeleton) return false;
  const std::size_t joints = skeleton->joint_count();
  if (joints == 0 || skeleton->parents.size() != joints || skeleton->centers.size() != joints) return false;
  // The chain reads the parent's matrix as already written: parents must come first.
  for (std::size_t j = 0; j < joints; ++j)
    if (skeleton->parents[j] >= static_cast<int>(j)) return false;
  const std::size_t n = local_rotation.count;
  const auto w = static_cast<std::uint32_t>(joints);
  if (!local_rotation.fits(n, w * 4) || !root_translation.fits(n, 3) || !world.fits(n, w * kAffineFloats) ||
      !skinning.fits(n, w * kAffineFloats))
    return false;
  return !world.overlaps(skinning) && !world.overlaps(local_rotation) && !world.overlaps(root_translation) &&
         !skinning.overlaps(local_rotation) && !skinning.overlaps(root_translation);
}

bool FkJob::run() const {
  if (!validate()) return false;
  const std::size_t count = local_rotation.count;
  if (count == 0) return true;
  // 256 walkers per task: a 25-joint chunk touches ~60 KiB per matrix field, small enough to stay in L2 while
  // the joint loop revisits parents, large enough that task overhead is noise.
  constexpr std::size_t kChunk = 256;
  if (count <= kChunk) {
    fk_range(*this, 0, count);
    return true;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kChunk),
                    [&](const tbb::blocked_range<std::size_t>& r) { fk_range(*this, r.begin(), r.end()); },
                    tbb::simple_partitioner());
  return true;
}

FkJob make_fk_job(const Skeleton& skeleton, SoaTable& walkers) {
  return {&skeleton, f32_view(walkers, kWalkerLocalRotation), f32_view(walkers, kWalkerRootTranslation),
          f32_view(walkers, kWalkerWorld), f32_view(walkers, kWalkerSkinning)};
}

}  // namespace strata
