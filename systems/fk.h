#pragma once
// Forward kinematics (the paper's equations 1-3), joint-major over all walkers at once.
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
#include "components/walker.h"

namespace strata {

// Computes world (F) and skinning (S) matrices for walkers [first, last) of `lanes`.
void fk_range(const Skeleton& skeleton, const WalkerLanes& lanes, std::size_t first, std::size_t last);
// All walkers, split across oneTBB worker threads in chunks of whole SIMD blocks. Each walker's result depends
// only on its own inputs, so the output is identical whatever the thread count.
void fk_system(const Skeleton& skeleton, const WalkerLanes& lanes);

}  // namespace strata
