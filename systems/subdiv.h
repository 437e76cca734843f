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

// Walker `w` of `lanes`: cage skinned into thread-local scratch, refined and given normals, into `out` (arrays of
// at least pad_to_lanes(surface.vertex_count) floats).
// `muscles`: the cage's muscle displacement (applied after skinning the cage, before refining), or null.
void subdiv_walker(const SubdivSurface& surface, const WalkerLanes& lanes, std::size_t w, const SkinOutput& out,
                   const MuscleDisplacementList* muscles = nullptr);

// Every walker, in parallel; `out` is resized like skin_system's.
void subdiv_system(const SubdivSurface& surface, const WalkerLanes& lanes, SkinnedCrowd& out,
                   const MuscleDisplacementList* muscles = nullptr);

}  // namespace strata
