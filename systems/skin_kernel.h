#pragma once
// The skinning kernel: linear blend skinning (the paper's equation 4) of one walker over a SkinLayout, SoA and
// vectorised. Matrices are broadcast per influence group; per vertex it blends them with the vertex's weights
// and transforms the rest position and normal (normals through the blended 3x3, renormalised).
//
// Runtime dispatch: the kernel is compiled twice (x86-64-v3, i.e. AVX2 + FMA, and the baseline x86-64 SSE2) and
// picks the one the CPU runs on first use, so one binary is fast on AVX2 machines and still correct elsewhere.
// systems/skin_reference.h is its scalar twin; tests hold both compiled bodies to it within 1e-5 m.
#include <array>
#include <span>
#include <vector>

#include <glm/vec3.hpp>

#include "components/skin_layout.h"
#include "components/walker.h"

namespace strata {

// Where one walker's skinned vertices go: six component arrays of at least layout.vertex_count floats (padded
// to the SIMD width: the kernel may write whole vectors).
struct SkinOutput {
  float *px, *py, *pz, *nx, *ny, *nz;
};

// The six arrays laid end to end in one block of 6 * stride floats (stride >= vertex count, a SIMD multiple).
inline SkinOutput skin_output_in(float* block, std::size_t stride) {
  return {block, block + stride, block + 2 * stride, block + 3 * stride, block + 4 * stride, block + 5 * stride};
}

// Muscle displacement for a layout skinned without muscle groups (the subdivision cage, whose vertex order the
// refinement stencils fix): per listed layout vertex its control points and coefficients, as in SkinLayout.
struct MuscleDisplacementList {
  std::vector<std::uint32_t> vertex;  // layout index
  std::vector<std::array<std::uint32_t, kMusclePointsPerVertex>> point;
  std::vector<std::array<float, kMusclePointsPerVertex>> coefficient;
};
MuscleDisplacementList make_muscle_displacement_list(const SkinLayout& layout, const MuscleBinding& binding,
                                                     std::span<const std::array<float, kMusclePointsPerVertex>> c);
// Moves the listed vertices of walker `w`'s skinned output along their (skinned, unit) normals by
// scale * sum_i c_i f[p_i]: the same displacement the muscle groups of skin_walker fuse in.
void apply_muscle_displacement(const MuscleDisplacementList& list, const WalkerLanes& lanes, std::size_t w,
                               const SkinOutput& out);

enum class SkinKernelIsa { Auto, Avx2Fma, Portable };
// Pins the body skin_walker uses (tests run both; Auto = what the CPU supports). Throws std::invalid_argument
// for Avx2Fma on a CPU without it.
void force_skin_kernel_isa(SkinKernelIsa isa);
// The body skin_walker runs now (never Auto), and its name ("avx2+fma", "sse2").
SkinKernelIsa skin_kernel_isa();
const char* skin_kernel_isa_name(SkinKernelIsa isa);

// Skins walker `w` of `lanes` (its skinning matrices and placement) into world space, layout order. When the
// layout carries a muscle binding and the lanes muscle columns, bound vertices then move along their skinned
// normal by the muscle displacement (scale * sum_i c_i f[p_i], systems/muscle.h). A blended normal of zero length
// comes out as zero (not NaN; the vertex then gets no displacement); the reference falls back to the rest normal.
void skin_walker(const SkinLayout& layout, const WalkerLanes& lanes, std::size_t w, const SkinOutput& out);

}  // namespace strata
