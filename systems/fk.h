#pragma once
// Forward kinematics (the paper's equations 1-3), joint-major over all walkers at once.
//
//   reads:  skeleton (parents, joint centres), local_rotation (joints*4), root_translation (3)
//   writes: world (joints*12), skinning (joints*12)
//
//   A(j) = rest frame of joint j            = T(c_j)             (H-Anim: identity rest rotations)
//   F(j) = F(p(j)) * R(j) * T(j)            with R(j) = T(c_j - c_p(j)), T(j) = the joint's local rotation
//   F(root) = T(root_translation + c_root) * T(root)
//   S(j) = F(j) * A(j)^-1 = F(j) * T(-c_j)  the skinning matrix: rest humanoid space -> posed humanoid space
//
// Walkers are lanes: for each joint (parents first), one loop over all walkers per matrix entry, which the
// compiler vectorises. Quaternions need not be normalised: the rotation is built with s = 2/|q|^2, so a scaled
// quaternion gives the same rotation and the zero quaternion gives identity instead of NaN.
#include <cstddef>

#include "components/skeleton.h"
#include "ecs/column_view.h"
#include "systems/job.h"

namespace strata {

struct FkJob {
  // Hierarchy in topological order (parents[j] < j) and joint centres, rest humanoid space (m).
  const Skeleton* skeleton = nullptr;
  // Local joint rotations, quaternion x, y, z, w per joint (component j*4 + c); need not be unit.
  ColumnView<const float> local_rotation;
  // HumanoidRoot translation (m), 3 components.
  ColumnView<const float> root_translation;
  // F(j), the joint's frame in humanoid space, 3x4 column-major per joint (component j*12 + k).
  ColumnView<float> world;
  // S(j) = F(j) A(j)^-1, rest humanoid space -> posed humanoid space, same layout as `world`.
  ColumnView<float> skinning;

  // Skeleton set, non-empty and topologically ordered; every view has the same rows and its expected width;
  // outputs overlap neither each other nor an input.
  bool validate() const;
  // All rows, split across oneTBB worker threads in chunks of whole SIMD blocks. Each walker's result depends
  // only on its own inputs, so the output is identical whatever the thread count. To run part of a table, give
  // the job views of those rows (ColumnView::rows).
  bool run() const;
};

// The job over every walker of `walkers` (a walker table, components/walker.h).
FkJob make_fk_job(const Skeleton& skeleton, SoaTable& walkers);

}  // namespace strata
