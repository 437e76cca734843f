#pragma once
// Ambient occlusion per skin vertex, baked once from a level's rest mesh: how much of the sky each vertex sees
// past the body's own surface within a short range (armpits, the crotch, under the chin and between the fingers
// are darker; the open back and chest are not). The shaded renderer (RenderQuality::High) darkens the ambient
// light by it; the sun keeps its shadow map.
//
// Baked per vertex rather than screen-space: it costs nothing per frame, has none of the screen-space method's
// halos or noise, and a crowd's bodies are one mesh shared by every walker. What it cannot know is the pose: a
// walker's swinging arm occludes its side as in the rest pose (arms hanging), which is close to where a walking arm
// is. Rays are cast on the CPU against a bounding-volume hierarchy of the rest triangles: cosine-weighted
// directions over the normal's hemisphere, a fixed pattern turned by a hash of the vertex (deterministic, no
// visible banding), each ray counting as occluded by how near its first hit is (an obscurance falloff).
#include <cstddef>
#include <memory>
#include <vector>

#include "components/body.h"
#include "components/mesh.h"

namespace strata {

struct OcclusionOptions {
  int rays = 48;           // per vertex
  float range = 0.25f;     // metres: hits farther than this do not occlude
};

struct VertexOcclusion {
  std::vector<float> open;  // per mesh vertex, in [0, 1]: 1 sees the whole hemisphere, 0 none of it
  double seconds = 0.0;     // the bake's wall time (0 when loaded from the disk cache)
  bool from_cache = false;
};

// Bakes `mesh` (rest positions; normals computed from the triangles when the mesh has none). Degenerate
// triangles are skipped; a vertex with a zero normal is left open (1). Parallel, deterministic for any thread count.
VertexOcclusion bake_vertex_occlusion(const Mesh& mesh, const OcclusionOptions& options = {});
// The same, cached on disk beside the body cache (rig/body_cache.h body_cache_directory), keyed by a hash of the
// mesh and the options: every process after the first loads it (level 0 bakes in under half a second optimised,
// many times that in a sanitizer build, where every test that draws at high quality paid it).
VertexOcclusion cached_vertex_occlusion(const Mesh& mesh, const OcclusionOptions& options = {});
// Level `level` (0..2; -1 the cage) of `body`, from cached_vertex_occlusion on first use and then kept in the body
// (Body::occlusion).
// nullptr when the body has no such level.
std::shared_ptr<const VertexOcclusion> body_vertex_occlusion(const Body& body, int level);

struct SubdivSurface;  // rig/subdiv_topology.h
// The occlusion of a refined surface's vertices (SubdivSurface numbering) from the cage's (cage mesh order),
// carried through each refinement step as its stencils' weighted average.
std::vector<float> refined_occlusion(const std::vector<float>& cage_open, const SubdivSurface& surface);

}  // namespace strata
