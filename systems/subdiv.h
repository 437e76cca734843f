#pragma once
// Subdivision system: every walker's body as the refined cage. Per walker: skin the cage with the skinning kernel
// (systems/skin_kernel.h) and move its muscle-bound vertices along their normals (the muscle layer's displacement
// on the cage, bound like any level), then
// the surface's stencils turn it into the refined positions level by level, then normals by area-weighted
// averaging over the refined triangles. Output goes into the same SkinnedCrowd the skin system fills (in the
// surface's vertex order, drawn with SubdivSurface::triangles), so the renderer draws it unchanged.
//
// Walkers run in parallel (oneTBB); each walker's output depends only on its own inputs, so any thread count
// gives the same bytes. Cage order: skin and muscle-deform the cage first, then subdivide, as
// OpenSubdiv's deforming-cage model intends; skinning a refined mesh with interpolated weights would give a
// different surface and cost the refined vertex count in skinning.
//
//   reads:  surface (cage layout, stencils, triangles), skinning (joints*12), placement (5), muscle_force (P,
//           optional), the cage's muscle displacement list (optional)
//   writes: SubdivWalkerJob: one walker's SkinOutput; SubdivJob: the SkinnedCrowd's six vertex arrays (prepared
//           beforehand: SkinnedCrowd::prepare)
#include <cstdint>
#include <span>

#include "rig/subdiv_topology.h"
#include "systems/skin.h"
#include "systems/skin_kernel.h"

namespace strata {

// dst[i] = sum of the row's weights times src, for x, y and z (SoA). dst must hold s.rows() floats per component,
// src s.source_count.
void apply_subdiv_stencils(const SubdivStencils& s, const float* sx, const float* sy, const float* sz, float* dx,
                           float* dy, float* dz);

// Unit vertex normals of `vertex_count` vertices: the sum of each incident triangle's (unnormalised, hence
// area-weighted) normal, renormalised. A vertex whose sum vanishes (only degenerate triangles: a collapsed limb)
// gets +Y, as compute_normals does, so no NaN leaves.
void area_weighted_normals(std::span<const std::uint32_t> triangles, std::size_t vertex_count, const float* px,
                           const float* py, const float* pz, float* nx, float* ny, float* nz);

// One walker: cage skinned into thread-local scratch (grown once per thread, reused), refined and given normals.
struct SubdivWalkerJob {
  const SubdivSurface* surface = nullptr;
  ColumnView<const float> skinning;      // S(j) per joint, 3x4 column-major (component j*12 + k)
  ColumnView<const float> placement;     // position x, y, z, heading, scale (components/walker.h)
  ColumnView<const float> muscle_force;  // force factor per control point, or empty
  // The cage's muscle displacement (applied after skinning the cage, before refining), or null.
  const MuscleDisplacementList* muscles = nullptr;
  std::size_t walker = 0;
  SkinOutput out;  // arrays of at least pad_to_lanes(surface->vertex_count) floats
  SkinningMode mode = SkinningMode::Linear;  // how the cage is skinned (its layout carries centres of rotation)

  // Surface set with stencil steps ending at its vertex count; the columns and the cage layout fit; the muscle
  // list's points and vertices in range; walker in range; out holds the refined surface.
  bool validate() const;
  bool run() const;
};

// The job for walker row `walker` of the walker table `walkers`.
SubdivWalkerJob make_subdiv_walker_job(const SubdivSurface& surface, const SoaTable& walkers, std::size_t walker,
                                       const SkinOutput& out, const MuscleDisplacementList* muscles = nullptr,
                                       SkinningMode mode = SkinningMode::Linear);

// Every walker, in parallel, one block each.
struct SubdivJob {
  const SubdivSurface* surface = nullptr;
  ColumnView<const float> skinning;
  ColumnView<const float> placement;
  ColumnView<const float> muscle_force;
  const MuscleDisplacementList* muscles = nullptr;
  SkinnedCrowd* out = nullptr;  // prepared: surface->vertex_count vertices, one block per row, no walker_ids
  SkinningMode mode = SkinningMode::Linear;

  bool validate() const;
  bool run() const;
};

// A job over every walker of `walkers` into `out`, which it prepares (the only allocation).
SubdivJob make_subdiv_job(const SubdivSurface& surface, const SoaTable& walkers, SkinnedCrowd& out,
                          const MuscleDisplacementList* muscles = nullptr, SkinningMode mode = SkinningMode::Linear);

}  // namespace strata
