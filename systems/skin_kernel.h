#pragma once
// The skinning kernel: linear blend skinning (the paper's equation 4) of one walker over a SkinLayout, SoA and
// vectorised. Matrices are broadcast per influence group; per vertex it blends them with the vertex's weights
// and transforms the rest position and normal (normals through the blended 3x3, renormalised).
//
// Three blending modes (SkinningMode, components/skin_layout.h): linear blending, dual quaternions, and optimised
// centres of rotation; every mode fuses the muscle displacement the same way.
//
// Runtime dispatch: the kernel is compiled three times (x86-64-v4, i.e. AVX-512 at 16 lanes; x86-64-v3, i.e.
// AVX2 + FMA; and the baseline x86-64 SSE2) and picks the best one the CPU runs on first use, so one binary is
// fast on AVX2 and AVX-512 machines and still correct elsewhere. reference/skin_reference.h is its scalar twin;
// tests hold every compiled body the CPU can run to it within 1e-5 m, in every mode.
//
//   SkinWalkerJob          reads:  layout (rest mesh, groups, weights, muscle coefficients), skinning
//                                  (joints*12), placement (5), muscle_force (P, optional) of one walker
//                          writes: that walker's SkinOutput (six arrays, layout order, world space)
//   MuscleDisplacementJob  reads:  displacement list, placement (scale), muscle_force (P) of one walker, and the
//                                  output's normals
//                          writes: the listed vertices' positions in a SkinOutput (moved along their normals)
#include <array>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "components/skin_layout.h"
#include "ecs/column_view.h"
#include "systems/job.h"

namespace strata {

// Where one walker's skinned vertices go: six component arrays of `capacity` floats each, at least
// pad_to_lanes(layout.vertex_count) (the kernel may write whole vectors).
struct SkinOutput {
  float *px = nullptr, *py = nullptr, *pz = nullptr, *nx = nullptr, *ny = nullptr, *nz = nullptr;
  std::size_t capacity = 0;  // floats per array
  bool holds(std::size_t floats) const { return px && py && pz && nx && ny && nz && capacity >= floats; }
};

// The six arrays laid end to end in one block of 6 * stride floats (stride >= vertex count, a SIMD multiple).
inline SkinOutput skin_output_in(float* block, std::size_t stride) {
  return {block, block + stride, block + 2 * stride, block + 3 * stride, block + 4 * stride, block + 5 * stride,
          stride};
}

// The walker columns every skinning job reads, checked together: the same rows, skinning a whole number of 3x4
// matrices (at most kMaxJointsPerRig joints), placement 5 wide, muscle_force either empty (components 0: no
// displacement) or 2..kMaxMusclePoints wide.
bool skin_columns_valid(const ColumnView<const float>& skinning, const ColumnView<const float>& placement,
                        const ColumnView<const float>& muscle_force);
// Whether `layout` can be skinned from `joints` joints and `muscle_points` force columns (0: none): groups inside
// the vertex range with 1..4 influences on existing joints, muscle points within the columns when both have them.
bool skin_layout_fits(const SkinLayout& layout, std::size_t joints, std::uint32_t muscle_points);
// Whether `layout` can be skinned in `mode`: centres of rotation need the layout's centres.
bool skin_mode_fits(const SkinLayout& layout, SkinningMode mode);

// Skins one walker into world space, layout order. When the layout carries a muscle binding and muscle_force is
// given, bound vertices then move along their skinned normal by the muscle displacement (scale * sum_i c_i
// f[p_i], systems/muscle.h). A blended normal of zero length comes out as zero (not NaN; the vertex then gets no
// displacement); the reference falls back to the rest normal.
struct SkinWalkerJob {
  const SkinLayout* layout = nullptr;
  ColumnView<const float> skinning;      // S(j) per joint, 3x4 column-major (component j*12 + k)
  ColumnView<const float> placement;     // position x, y, z, heading, scale (components/walker.h)
  ColumnView<const float> muscle_force;  // force factor per control point, or empty: no displacement
  std::size_t walker = 0;                // row of the views
  SkinOutput out;
  SkinningMode mode = SkinningMode::Linear;  // CentresOfRotation needs the layout's centres (set_cor_centres)

  // The columns (skin_columns_valid), the layout fits them and the mode, walker in range, out holds it.
  bool validate() const;
  bool run() const;
};

// Muscle displacement for a layout skinned without muscle groups (the subdivision cage, whose vertex order the
// refinement stencils fix): per listed layout vertex its control points and coefficients, as in SkinLayout.
struct MuscleDisplacementList {
  std::vector<std::uint32_t> vertex;  // layout index
  std::vector<std::array<std::uint32_t, kMusclePointsPerVertex>> point;
  std::vector<std::array<float, kMusclePointsPerVertex>> coefficient;
};
MuscleDisplacementList make_muscle_displacement_list(const SkinLayout& layout, const MuscleBinding& binding,
                                                     std::span<const std::array<float, kMusclePointsPerVertex>> c);
// Moves the listed vertices of one walker's skinned output along their (skinned, unit) normals by
// scale * sum_i c_i f[p_i]: the same displacement the muscle groups of SkinWalkerJob fuse in.
// With an empty list or no muscle_force columns there is nothing to move: valid, and run() writes nothing.
struct MuscleDisplacementJob {
  const MuscleDisplacementList* list = nullptr;
  ColumnView<const float> placement;     // its scale (component 4)
  ColumnView<const float> muscle_force;  // force factor per control point, or empty
  std::size_t walker = 0;
  SkinOutput out;                        // normals read, positions of listed vertices moved

  // List set with equal-length arrays; placement 5 wide; walker in range; every point inside muscle_force and
  // every vertex inside out (when there is anything to move).
  bool validate() const;
  bool run() const;
};

namespace detail {
// The kernels behind the jobs, for jobs that validated their whole crowd once (skin, subdiv): no checks.
void skin_walker(const SkinLayout& layout, const ColumnView<const float>& skinning,
                 const ColumnView<const float>& placement, const ColumnView<const float>& muscle_force,
                 std::size_t w, const SkinOutput& out, SkinningMode mode = SkinningMode::Linear);
void apply_muscle_displacement(const MuscleDisplacementList& list, const ColumnView<const float>& placement,
                               const ColumnView<const float>& muscle_force, std::size_t w, const SkinOutput& out);
}  // namespace detail

// Views of the walker table columns the skinning jobs read; muscle_force is empty for a table made without
// muscle points (its single placeholder column).
struct SkinColumns {
  ColumnView<const float> skinning, placement, muscle_force;
};
SkinColumns skin_columns(const SoaTable& walkers);
// The job for walker row `walker` of the walker table `walkers`.
SkinWalkerJob make_skin_walker_job(const SkinLayout& layout, const SoaTable& walkers, std::size_t walker,
                                   const SkinOutput& out, SkinningMode mode = SkinningMode::Linear);

enum class SkinKernelIsa { Auto, Avx2Fma, Portable, Avx512 };
// Whether this CPU runs that body (Auto and Portable: always).
bool skin_kernel_isa_supported(SkinKernelIsa isa);
// Pins the body skin_walker uses (tests run each the CPU supports; Auto = the best the CPU supports). Throws
// std::invalid_argument for Avx2Fma or Avx512 on a CPU without it.
void force_skin_kernel_isa(SkinKernelIsa isa);
// The body skin_walker runs now (never Auto), and its name ("avx512", "avx2+fma", "sse2").
SkinKernelIsa skin_kernel_isa();
const char* skin_kernel_isa_name(SkinKernelIsa isa);

}  // namespace strata
