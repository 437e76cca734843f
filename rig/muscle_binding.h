#pragma once
// Binding skin vertices to the muscle layer (the paper, section 6), once per body level at rest:
//   1. A vertex may bind to a muscle when its part is one of the muscle's parts and its rest distance from the
//      action line (the segment origin-insertion) is below the muscle's radius; it binds to the nearest such line.
//   2. It attaches to that line's nearest three control points with weights inversely proportional to distance,
//      summing to 1.
//   3. Each control point's weight is spread over its force vectors inversely to the angle between the force
//      vector (rest frame) and the vector from the control point to the vertex.
// Beyond the paper, a radial falloff (components/muscle.h MuscleBinding::falloff) fades the effect to zero at
// the edge of the muscle's reach.
//
// The per-frame skinning kernel never sees force vectors: muscle_coefficients() folds weight x falloff x
// shares x magnitudes x gains into one coefficient per (vertex, control point), recomputed only when a force
// value is edited, so the displacement costs three multiply-adds per vertex per frame.
#include <array>
#include <memory>
#include <vector>

#include "components/body.h"

#include "components/mesh.h"
#include "components/muscle.h"
#include "rig/body_rig.h"

namespace strata {

// Binds `mesh` (rest pose) to `set`. Deterministic; vertices whose part matches no muscle stay unbound.
MuscleBinding bind_muscles(const Mesh& mesh, const MuscleSet& set);

// Per bound vertex b and slot i: falloff[b] * weight[b][i] * sum_a share * magnitude_a * gains.of(line[b]).
// The displacement of b along its normal is then sum_i coefficient[b][i] * f[point[b][i]] (times the walker's
// scale).
std::vector<std::array<float, kMusclePointsPerVertex>> muscle_coefficients(const MuscleSet& set,
                                                                           const MuscleBinding& binding,
                                                                           const MuscleGains& gains = {});

// The muscle layer of a rig: `set` bound to every level of `body`.
std::shared_ptr<const MuscleRig> bind_muscle_rig(MuscleSet set, const Body& body);

// The shipped muscles (data/muscles.json) on the shipped body and skeleton (rig/body_rig.h default_bound_body),
// bound once per process.
// Defined in rig/body_rig.cpp, beside the bodies.
std::shared_ptr<const MuscleRig> default_muscle_rig(ShippedBody body = kDefaultShippedBody);

}  // namespace strata
