#pragma once
// What each skin vertex is dressed in: bare skin, the top (shirt), the bottom (trousers), shoes, hair, or an eye
// (iris and the white around it).
// The shaded renderer (RenderQuality::High) colours each walker's body by these classes with that walker's own
// palette (render/appearance.h), so a crowd is people in clothes rather than copies of one clay figure.
//
// Classes come from the paper's part names (components/mesh.h paper_part_names): the torso, collars and upper
// arms are the top (a shirt, its short sleeves cut square across the upper arm), hip, thighs and shins the bottom, feet and toes shoes, the eyes eyes,
// the rest skin; an eyeball has an iris facing forward on a white ball. Where one class meets another inside a part, the edge is a cut: the shirt ends at a level
// waistline, a shoe at a level top, the hair at a hairline over the forehead and ears. A cut is stored per vertex
// as two classes and a signed distance (metres) to the cut, which the renderer interpolates and thresholds per
// pixel: a per-vertex class alone gives an edge that zigzags along the triangles, worse the coarser the level.
// A mesh whose parts are not the paper's (an imported body) is all skin: guessing clothes from unknown part names
// would paint them at random.
#include <cstdint>
#include <vector>

#include "components/mesh.h"
#include "components/skin_layout.h"

namespace strata {

enum class SurfaceMaterial : std::uint8_t { Skin, Top, Bottom, Shoes, Hair, Eyes, Sclera };
inline constexpr std::uint8_t kSurfaceMaterialCount = 7;

// Per vertex: `classes` packs the class on the cut's positive side (low four bits) and on its negative side (high
// four bits); `cut` is the signed distance to the cut. A vertex away from every cut has one class on both sides.
struct SurfaceClasses {
  std::vector<std::uint8_t> classes;
  std::vector<float> cut;

  std::size_t size() const { return classes.size(); }
  // The class at vertex v itself.
  SurfaceMaterial at(std::size_t v) const {
    return static_cast<SurfaceMaterial>(cut[v] >= 0.0f ? classes[v] & 15u : classes[v] >> 4);
  }
};

// Mesh order.
SurfaceClasses surface_materials(const Mesh& mesh);
// The same in a skin layout's vertex order (layout.original maps layout -> mesh vertex).
SurfaceClasses layout_materials(const Mesh& mesh, const SkinLayout& layout);

struct SubdivSurface;  // rig/subdiv_topology.h
// A refined surface's (SubdivSurface numbering), carried from the cage through each refinement step: a new vertex
// takes the class pair of its stencil's heaviest source, and the weighted average of the distances (a stencil is
// an affine combination, so a plane's distance carries over exactly).
SurfaceClasses refined_materials(const Mesh& cage, const SubdivSurface& surface);

}  // namespace strata
