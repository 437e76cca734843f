#pragma once
// Texture coordinates carried from a source surface onto a remeshed copy of it (the MakeHuman body's levels, which
// one Loop step and the collapse cut from the fitted source mesh). Per triangle corner, so UV seams need no split
// vertex.
//
// Why a transfer and not UVs carried through the refinement and the collapse: the collapse merges vertices across
// the source's seams (a vertex on a seam has two UVs, one per side), so carrying them would mean a seam-aware
// collapse (forbidding or steering merges across charts) in code the procedural body shares. Projection gives
// each level corner the UV of the nearest point of the source surface instead, within one chart per triangle, so
// a seam falls along the level's own edges nearest the source's seam.
//
// Per target triangle: the source triangle nearest its centroid; from there, per corner, a walk over the source
// surface towards the corner (across the edge the corner lies beyond, never across a UV seam: an edge whose two
// sides carry different UVs), and the UV of the nearest point of the triangles walked, interpolated
// barycentrically. A vertex inside a chart so gets one UV from every triangle around it (the walks end in the same
// source triangle), and a target triangle across a source seam is clamped to one side of it instead of spanning
// the texture between the seam's two sides (which nearest-point projection alone did wherever one island is cut:
// an arm's cylinder, for one).
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "components/mesh.h"

namespace strata {

struct UvSource {
  std::span<const glm::vec3> positions;
  std::span<const std::uint32_t> triangles;
  std::span<const glm::vec2> corner_uvs;  // 3 per triangle
};

// Per corner of `target` (3 per triangle, the order of target.triangles). Throws std::invalid_argument when the
// source has no triangles, its corner UVs do not match its triangles, or an index is out of range. Deterministic.
std::vector<glm::vec2> transfer_corner_uvs(const UvSource& source, const Mesh& target);

}  // namespace strata
