#pragma once
// The X3D H-Anim skin a skeleton file carried (skinCoord points, IndexedFaceSet triangles, per-joint
// skinCoordIndex/skinCoordWeight) as a Mesh and SkinBinding.
#include <optional>

#include "components/body.h"
#include "components/skeleton.h"

namespace strata {

// Empty when the skeleton has no skin or no weights. Per vertex the four largest weights are kept and
// renormalised. X3D leaves a vertex no joint lists where it is; here it follows HumanoidRoot instead, so it
// travels with the walker rather than staying behind at the origin. Parts: one per joint that weights vertices
// ("skin_<joint>"), by each vertex's strongest joint.
std::optional<BodyLevel> skin_from_skeleton(const Skeleton& skeleton);

}  // namespace strata
