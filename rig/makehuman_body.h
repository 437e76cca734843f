#pragma once
// The modelled default body: the MakeHuman hm08 base mesh (CC0, an artist's quad mesh), shipped compact in
// data/makehuman_body.bin (io/makehuman_pack.h), fitted to an H-Anim skeleton and brought to the paper's three
// resolution levels and a subdivision cage, each vertex tagged with one of the 53 paper parts.
//
// Route:
//   1. fit (fit_makehuman_to_skeleton): scale to the skeleton's height, then pose the mesh from MakeHuman's
//      A-pose into the skeleton's rest by its own weights, each limb segment turned onto the skeleton's segment
//      and stretched along it, blended by dual quaternions (rig/skin twin's rule) so the shoulders keep their
//      volume while the arms come down ~45 deg; elbows and knees moved onto their limb's middle first (MakeHuman's
//      elbow sits 1.8 cm behind its arm's, and a limb bent off its middle loses volume), the fit run again;
//   2. refine: one Loop step (OpenSubdiv; 13,380 -> 53,514 vertices), so the finest level is simplified from a
//      smooth surface instead of interpolating new vertices on the quads' flat facets;
//   3. simplify: the shared collapse (rig/surface_simplify.h) to exactly 17,953 / 8,923 / 5,133 vertices, each
//      level from the one above, and a 1,800-vertex cage, the surface closed and 2-manifold throughout;
//   4. parts: each vertex takes the part of the source vertex it descends from, through the refinement's
//      stencils and the collapse (the part of its strongest MakeHuman bone, io/makehuman.cpp's documented map);
//   5. texture coordinates: MakeHuman's, per corner (Mesh::corner_uvs: its seams give 1,137 UVs more than
//      vertices), projected onto each level and the cage from the fitted source (rig/uv_transfer.h) rather than
//      carried through the collapse, which merges vertices across seams.
// The hm08 body is closed (genus 0, the eyes and mouth lidded over), so no hole needs filling.
#include "io/makehuman_pack.h"
#include "rig/body_generator.h"

namespace strata {

// The source's positions posed and fitted to `target`'s rest (needs the default skeleton's 25 joint names;
// throws std::invalid_argument naming a missing one). Deterministic; no NaN for any finite input.
std::vector<glm::vec3> fit_makehuman_to_skeleton(const MakeHumanSource& source, const Skeleton& target);

BodyLevels derive_makehuman_body(const MakeHumanSource& source, const Skeleton& target,
                                 const BodyOptions& options = {});

// The shipped source (data/makehuman_body.bin) unpacked.
MakeHumanSource shipped_makehuman_source();

// The shipped body fitted to the default skeleton, derived on first use (thread-safe, once per process) and cached
// on disk beside the procedural body (rig/body_cache.h).
const BodyLevels& makehuman_default_body();

}  // namespace strata
