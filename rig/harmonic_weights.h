#pragma once
// Harmonic interpolation of skin weights across a region of a mesh: the weights of the region's vertices become
// the smoothest field (least Dirichlet energy, cotangent Laplacian) that meets the binding of the vertices around
// the region. This is the "harmonic" blend of a step-3 selection (data/binding_overrides.json, rig/binding.h).
//
// Why: where two or three parts meet at a ball joint (the groin, the armpit) the part boundary is no line along
// a bone, so step 2's blend along one bone axis does not apply, and inverse-distance weights between two joint
// centres vary with the wrong coordinate (sacroiliac and a hip sit at the same height, so their ratio changes
// across the body, not down the thigh). A harmonic field spreads each transition over the whole region, whatever
// its shape, and meets three joints at the crotch symmetrically. LBS folds a triangle when a weight changes faster
// than about 1 / (lever x sin(angle)), so the region's size, not a hand-tuned falloff, sets the slope.
#include <cstdint>
#include <span>
#include <vector>

#include "components/mesh.h"

namespace strata {

struct JointWeight {
  int joint = 0;
  double weight = 0.0;
};

struct HarmonicWeightOptions {
  // Every weight is lowered by this and clamped at 0 before the weights are renormalised (a soft threshold), so
  // a joint at the far side of the region does not add a sub-percent influence to every vertex, and still fades
  // out continuously. Measured over the default walk (strata report skin): a hard cut at 0.01 left the closest
  // triangle at 8.8 % of its rest area at level 1 (5 % counts as collapsed), the soft one at 26 %.
  double min_weight = 0.01;
  // Successive over-relaxation: stop when no weight moves more than `tolerance` in a sweep, or after
  // `max_sweeps`. 1.9 converges in a few hundred sweeps on the groin of the finest default level (~60 edge rings
  // across); plain Gauss-Seidel (1.0) needed thousands.
  double relaxation = 1.9;
  double tolerance = 1e-9;
  int max_sweeps = 20000;
};

// One list of (joint, weight) per mesh vertex: for every vertex with free[v] != 0 that is connected through free
// vertices to a vertex with free == 0, the harmonic weights (after the min_weight threshold, summing to 1);
// empty for the others (fixed vertices, and free islands that touch no fixed vertex and so have nothing to
// interpolate). Cotangent edge weights are clamped at 0 (an M-matrix: the maximum principle keeps every weight
// between its smallest and largest boundary value, so no negative lobes). A list may hold more than kMaxInfluences
// joints; the binder keeps the four largest (the shipped selections never reach more than four). Deterministic:
// sequential sweeps in vertex order. Throws std::invalid_argument when the sizes of mesh, binding and free differ.
std::vector<std::vector<JointWeight>> harmonic_weights(const Mesh& mesh, const SkinBinding& binding,
                                                       std::span<const std::uint8_t> free,
                                                       const HarmonicWeightOptions& options = {});

}  // namespace strata
