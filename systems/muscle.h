#pragma once
// Muscle system (frame script step 4, after FK, before skinning): for every walker and action line, places the
// origin and insertion on their joints (skinning matrices S = F A^-1 applied to the rest attachment points),
// interpolates the inner control points, and writes each point's position, local frame, length and force factor
// into the walker's muscle columns (components/walker.h). The force model is in components/muscle.h:
//     f = L / max(l, min_length_ratio * L) - 1      (0 at rest, > 0 shortened, < 0 lengthened, never inf/NaN)
// The skinning kernel turns the factors into a displacement along each bound vertex's skinned normal.
//
// Walkers run in parallel (oneTBB) and each writes only its own lane, so the output is the same for any thread
// count. Control points are few (60 for the default set), so the loop is per walker, scalar; vectorising across
// walkers was not worth its complexity at about 4 % of the skinning step's cost (0.69 ms against 19.2 ms for 1,000 walkers; docs/skin.md).
#include "components/muscle.h"
#include "components/walker.h"

namespace strata {

void muscle_system(const MuscleSet& set, const WalkerLanes& lanes);

// The same for one walker (the system's body; tests and tools call it directly).
void muscle_walker(const MuscleSet& set, const WalkerLanes& lanes, std::size_t walker);

}  // namespace strata
