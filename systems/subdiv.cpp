#include "systems/subdiv.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "components/walker.h"
#include "ecs/aligned_buffer.h"

namespace strata {

__attribute__((target_clones("arch=x86-64-v3", "default"))) void apply_subdiv_stencils(const SubdivStencils& s, const float* __restrict sx, const float* __restrict sy,
                           const float* __restrict sz, float* __restrict dx, float* __restrict dy,
                           float* __restrict dz) {
  const std::uint32_t* __restrict offsets = s.offsets.data();
  const std::uint32_t* __restrict indices = s.indices.data();
  const float* __restrict weights = s.weights.data();
  const std::size_t rows = s.rows();
  // A row is a short gather (4 terms for an edge point, valence + 1 for a vertex point): scalar accumulation with
  // the three components interleaved keeps three independent FMA chains in flight, which is what bounds it.
  for (std::size_t i = 0; i < rows; ++i) {
    float x = 0.0f, y = 0.0f, z = 0.0f;
    for (std::uint32_t k = offsets[i], end = offsets[i + 1]; k < end; ++k) {
      const std::uint32_t j = indices[k];
      const float w = weights[k];
      x += w * sx[j];
      y += w * sy[j];
      z += w * sz[j];
    }
    dx[i] = x;
    dy[i] = y;
    dz[i] = z;
  }
}

__attribute__((target_clones("arch=x86-64-v3", "default"))) void area_weighted_normals(std::span<const std::uint32_t> triangles, std::size_t vertex_count, const float* px,
                           const float* py, const float* pz, float* nx, float* ny, float* nz) {
  std::fill(nx, nx + vertex_count, 0.0f);
  std::fill(ny, ny + vertex_count, 0.0f);
  std::fill(nz, nz + vertex_count, 0.0f);
  // Scatter each face normal to its three corners. The alternative, gathering per vertex over an ordered one-ring
  // (no read-modify-write, but every face normal computed three times and a ring table per rig), is not measured
  // yet; at 10-18 ns per vertex the normals are now the larger half of a walker's cost, so it is the next to try.
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
    const std::uint32_t a = triangles[t], b = triangles[t + 1], c = triangles[t + 2];
    const float ux = px[b] - px[a], uy = py[b] - py[a], uz = pz[b] - pz[a];
    const float vx = px[c] - px[a], vy = py[c] - py[a], vz = pz[c] - pz[a];
    const float fx = uy * vz - uz * vy, fy = uz * vx - ux * vz, fz = ux * vy - uy * vx;
    nx[a] += fx, ny[a] += fy, nz[a] += fz;
    nx[b] += fx, ny[b] += fy, nz[b] += fz;
    nx[c] += fx, ny[c] += fy, nz[c] += fz;
  }
  // Branch-free so it vectorises: a vanished sum (|n|^2 below ~1e-30, i.e. faces of ~1e-15 m^2) becomes +Y.
  for (std::size_t i = 0; i < vertex_count; ++i) {
    const float x = nx[i], y = ny[i], z = nz[i];
    const float len2 = x * x + y * y + z * z;
    const bool usable = len2 > 1e-30f;
    const float inv = usable ? 1.0f / std::sqrt(usable ? len2 : 1.0f) : 0.0f;
    nx[i] = x * inv;
    ny[i] = usable ? y * inv : 1.0f;
    nz[i] = z * inv;
  }
}

namespace {

// Per-thread scratch: the skinned cage (six arrays, the kernel's output format) and two ping-pong sets of
// positions for the intermediate levels. Reused across walkers and frames; grows only when a deeper surface or
// larger cage arrives.
struct SubdivScratch {
  AlignedBuffer<float> cage;
  AlignedBuffer<float> level[2];
};

void ensure(AlignedBuffer<float>& b, std::size_t floats) {
  if (b.size() < floats) b.reset(floats);
}

// Whether the surface, columns and muscle list of a job agree (SubdivWalkerJob and SubdivJob share it).
bool subdiv_inputs_valid(const SubdivSurface* surface, const ColumnView<const float>& skinning,
                         const ColumnView<const float>& placement, const ColumnView<const float>& muscle_force,
                         const MuscleDisplacementList* muscles, SkinningMode mode) {
  if (!surface || surface->steps.empty() || !skin_columns_valid(skinning, placement, muscle_force)) return false;
  if (!skin_mode_fits(surface->cage_layout, mode)) return false;
  if (!skin_layout_fits(surface->cage_layout, skinning.components / kAffineFloats, muscle_force.components))
    return false;
  // Each step reads the previous level (the cage first) and the last one gives the surface's vertices. The
  // stencils' own indices are checked once, when make_subdiv_surface builds them (immutable rig data); walking
  // every term here would cost about as much as applying them.
  std::size_t source = surface->cage_layout.vertex_count;
  for (const SubdivStencils& step : surface->steps) {
    if (step.source_count != source || step.rows() == 0 || step.weights.size() != step.indices.size() ||
        step.offsets.back() != step.indices.size())
      return false;
    source = step.rows();
  }
  if (source != surface->vertex_count || surface->triangles.size() % 3 != 0) return false;
  if (muscles && !muscles->vertex.empty() && muscle_force.components > 0) {
    if (muscles->point.size() != muscles->vertex.size() || muscles->coefficient.size() != muscles->vertex.size())
      return false;
    for (std::size_t i = 0; i < muscles->vertex.size(); ++i) {
      if (muscles->vertex[i] >= surface->cage_layout.vertex_count) return false;
      for (const std::uint32_t p : muscles->point[i])
        if (p >= muscle_force.components) return false;
    }
  }
  return true;
}

// Walker `w` of a validated job.
void subdiv_walker(const SubdivSurface& surface, const ColumnView<const float>& skinning,
                   const ColumnView<const float>& placement, const ColumnView<const float>& muscle_force,
                   const MuscleDisplacementList* muscles, std::size_t w, const SkinOutput& out, SkinningMode mode) {
  thread_local SubdivScratch scratch;
  const std::size_t cage_stride = pad_to_lanes(surface.cage_layout.vertex_count);
  ensure(scratch.cage, 6 * cage_stride);
  const SkinOutput cage = skin_output_in(scratch.cage.data(), cage_stride);
  detail::skin_walker(surface.cage_layout, skinning, placement, muscle_force, w, cage, mode);
  if (muscles) detail::apply_muscle_displacement(*muscles, placement, muscle_force, w, cage);
  const float* sx = cage.px;
  const float* sy = cage.py;
  const float* sz = cage.pz;
  for (std::size_t k = 0; k < surface.steps.size(); ++k) {
    const SubdivStencils& step = surface.steps[k];
    float *dx = out.px, *dy = out.py, *dz = out.pz;
    if (k + 1 < surface.steps.size()) {  // an intermediate level: into scratch
      const std::size_t stride = pad_to_lanes(step.rows());
      AlignedBuffer<float>& buffer = scratch.level[k % 2];
      ensure(buffer, 3 * stride);
      dx = buffer.data(), dy = dx + stride, dz = dy + stride;
    }
    apply_subdiv_stencils(step, sx, sy, sz, dx, dy, dz);
    sx = dx, sy = dy, sz = dz;
  }
  area_weighted_normals(surface.triangles, surface.vertex_count, out.px, out.py, out.pz, out.nx, out.ny, out.nz);
}

}  // namespace

bool SubdivWalkerJob::validate() const {
  return subdiv_inputs_valid(surface, skinning, placement, muscle_force, muscles, mode) && walker < skinning.count &&
         out.holds(pad_to_lanes(surface->vertex_count));
}

bool SubdivWalkerJob::run() const {
  if (!validate()) return false;
  subdiv_walker(*surface, skinning, placement, muscle_force, muscles, walker, out, mode);
  return true;
}

bool SubdivJob::validate() const {
  if (!out || !subdiv_inputs_valid(surface, skinning, placement, muscle_force, muscles, mode)) return false;
  const std::size_t floats = out->stride * skinning.count;
  return out->vertex_count == surface->vertex_count && out->stride == pad_to_lanes(surface->vertex_count) &&
         out->walkers == skinning.count && out->walker_ids.empty() && out->px.size() >= floats &&
         out->py.size() >= floats && out->pz.size() >= floats && out->nx.size() >= floats &&
         out->ny.size() >= floats && out->nz.size() >= floats;
}

bool SubdivJob::run() const {
  if (!validate()) return false;
  // One walker per task: a walker at level 2 is ~0.5 ms of work, far above the scheduling cost.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, skinning.count, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t w = r.begin(); w < r.end(); ++w)
                        subdiv_walker(*surface, skinning, placement, muscle_force, muscles, w, out->block(w), mode);
                    },
                    tbb::simple_partitioner());
  return true;
}

SubdivWalkerJob make_subdiv_walker_job(const SubdivSurface& surface, const SoaTable& walkers, std::size_t walker,
                                       const SkinOutput& out, const MuscleDisplacementList* muscles,
                                       SkinningMode mode) {
  const SkinColumns c = skin_columns(walkers);
  return {&surface, c.skinning, c.placement, c.muscle_force, muscles, walker, out, mode};
}

SubdivJob make_subdiv_job(const SubdivSurface& surface, const SoaTable& walkers, SkinnedCrowd& out,
                          const MuscleDisplacementList* muscles, SkinningMode mode) {
  out.prepare(surface.vertex_count, walkers.size());
  const SkinColumns c = skin_columns(walkers);
  return {&surface, c.skinning, c.placement, c.muscle_force, muscles, &out, mode};
}

}  // namespace strata
