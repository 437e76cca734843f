#pragma once
// The OpenSubdiv side of the cage: a Far::TopologyRefiner over a triangle cage with Strata's subdivision options.
// The one header that includes OpenSubdiv; rig/subdiv_topology.cpp, the subdiv report and the tests use it, and
// nothing a library consumer includes pulls it in (OpenSubdiv stays a private dependency).
#include <memory>

#include <opensubdiv/far/topologyRefiner.h>

#include "components/mesh.h"

namespace strata {

// Loop scheme (the cage is all triangles; Catmull-Clark would first split every triangle into three quads and
// triple the vertex count for the same smoothness). Vertex boundary EDGE_AND_CORNER, so an open boundary (a cut
// neck, an imported cage with holes) keeps its edge instead of shrinking inwards as the default NONE does, and
// corners stay put. Face-varying UVs, when the cage has them (one channel, indexed like the triangles), are
// smooth in the interior and linear at their corners (FVAR_LINEAR_CORNERS_ONLY), the usual choice for skins.
// Unrefined: the caller refines (RefineUniform) to the level it needs. Throws std::invalid_argument when the
// cage is empty or OpenSubdiv rejects its topology.
std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> make_cage_refiner(const Mesh& cage);

}  // namespace strata
