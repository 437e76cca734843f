#include "systems/skin_kernel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

#include "components/walker.h"

namespace strata {
namespace {

// The walker's force factors times its scale, per control point (see MuscleSet::point_count's cap).
struct MuscleInput {
  const float* force = nullptr;
};

// One group's vertices [first, first + count) with `k` influences whose (placement-premultiplied) 3x4 matrices
// are m[j][0..11]. Writes SoA results. Kept a plain loop over restrict pointers with no branches, so GCC
// vectorises it (see fk.cpp for why the normal's guard is an add rather than a compare).
//
// Muscle groups (Muscle = true) then move each vertex along its skinned, renormalised normal by
// d = c0 f[p0] + c1 f[p1] + c2 f[p2] (three gathers from the walker's few hundred bytes of force factors, which
// stay in L1), fused here so positions are written once; a separate displacement pass would read and write the
// whole output again.
// A column's row `first`, or null for a column this layout does not fill (no muscles, fewer influences):
// `data() + first` on an empty column is arithmetic on a null pointer, undefined even when never dereferenced.
template <class Column>
[[gnu::always_inline]] inline auto column_at(const Column& column, std::uint32_t first) -> decltype(column.data()) {
  return column.data() == nullptr ? nullptr : column.data() + first;
}

// The vertex count a group loop runs: `count` itself, or (Whole) the same count with the compiler told it is a
// whole number of 16-vertex blocks, so no vectorised loop needs a scalar remainder (skin_groups' split below).
template <bool Whole>
[[gnu::always_inline]] inline std::size_t whole_vectors(std::uint32_t count) {
  return Whole ? std::size_t(count) & ~(kSimdLaneFloats - 1) : std::size_t(count);
}

template <int K, bool Muscle, bool Whole, bool Rigid = false>
[[gnu::always_inline]] inline void skin_group(const SkinLayout& L, std::uint32_t first, std::uint32_t count, const float (*m)[12],
                const float* __restrict force, float* __restrict ox, float* __restrict oy, float* __restrict oz,
                float* __restrict onx, float* __restrict ony, float* __restrict onz, float normal_scale = 1.0f) {
  const float* __restrict px = column_at(L.px, first);
  const float* __restrict py = column_at(L.py, first);
  const float* __restrict pz = column_at(L.pz, first);
  const float* __restrict nx = column_at(L.nx, first);
  const float* __restrict ny = column_at(L.ny, first);
  const float* __restrict nz = column_at(L.nz, first);
  const float* __restrict w1 = column_at(L.weight[1], first);
  const float* __restrict w2 = column_at(L.weight[2], first);
  const float* __restrict w3 = column_at(L.weight[3], first);
  const std::int32_t* __restrict p0 = column_at(L.muscle_point[0], first);
  const std::int32_t* __restrict p1 = column_at(L.muscle_point[1], first);
  const std::int32_t* __restrict p2 = column_at(L.muscle_point[2], first);
  const float* __restrict c0 = column_at(L.muscle_coefficient[0], first);
  const float* __restrict c1 = column_at(L.muscle_coefficient[1], first);
  const float* __restrict c2 = column_at(L.muscle_coefficient[2], first);
  // A local copy: the compiler cannot prove the outputs never alias `m`, and would reload it every vertex.
  // Weights sum to 1 (the layout renormalised them), so sum_k w_k M_k = M_0 + sum_{k>0} w_k (M_k - M_0): one
  // multiply-add per influence beyond the first instead of a multiply per influence, and w_0 is never read (4
  // bytes a vertex less to stream). The implicit w_0 differs from the stored one by float rounding (1e-7).
  float M[K][12];
  for (int k = 0; k < K; ++k)
    for (int c = 0; c < 12; ++c) M[k][c] = k == 0 ? m[0][c] : m[k][c] - m[0][c];
  // Outputs offset once and a 64-bit index: with `first + i` in 32 bits the addresses may wrap, which GCC
  // cannot vectorise.
  ox += first, oy += first, oz += first, onx += first, ony += first, onz += first;
  const std::size_t n = whole_vectors<Whole>(count);
  for (std::size_t i = 0; i < n; ++i) {
    // Twelve named scalars rather than a float[12]: GCC keeps an array local in memory and then refuses to
    // vectorise the vertex loop ("no vectype"); scalars it vectorises.
    float v1 = 0.0f, v2 = 0.0f, v3 = 0.0f;
    if constexpr (K > 1) v1 = w1[i];
    if constexpr (K > 2) v2 = w2[i];
    if constexpr (K > 3) v3 = w3[i];
    auto blend = [&](int c) {
      float r = M[0][c];
      if constexpr (K > 1) r += v1 * M[1][c];
      if constexpr (K > 2) r += v2 * M[2][c];
      if constexpr (K > 3) r += v3 * M[3][c];
      return r;
    };
    const float b0 = blend(0), b1 = blend(1), b2 = blend(2), b3 = blend(3), b4 = blend(4), b5 = blend(5);
    const float b6 = blend(6), b7 = blend(7), b8 = blend(8), b9 = blend(9), b10 = blend(10), b11 = blend(11);
    const float a = nx[i], c = ny[i], d = nz[i];
    const float qx = b0 * a + b3 * c + b6 * d;
    const float qy = b1 * a + b4 * c + b7 * d;
    const float qz = b2 * a + b5 * c + b8 * d;
    // Rigid (one joint whose matrix is a rotation times the walker's scale): the normal's length is that scale,
    // known per group, so a multiply replaces the per-vertex reciprocal square root.
    float inv;
    if constexpr (Rigid)
      inv = normal_scale;
    else
      inv = 1.0f / std::sqrt(qx * qx + qy * qy + qz * qz + 1e-30f);
    const float ux = qx * inv, uy = qy * inv, uz = qz * inv;
    onx[i] = ux;
    ony[i] = uy;
    onz[i] = uz;
    const float x = px[i], y = py[i], z = pz[i];
    float sx = b0 * x + b3 * y + b6 * z + b9;
    float sy = b1 * x + b4 * y + b7 * z + b10;
    float sz = b2 * x + b5 * y + b8 * z + b11;
    if constexpr (Muscle) {
      const float disp = c0[i] * force[p0[i]] + c1[i] * force[p1[i]] + c2[i] * force[p2[i]];
      sx += disp * ux;
      sy += disp * uy;
      sz += disp * uz;
    }
    ox[i] = sx;
    oy[i] = sy;
    oz[i] = sz;
  }
}

// Per joint, what the non-linear modes blend: the rigid part of the world matrix P * S_j as a unit dual quaternion
// (real x, y, z, w, then dual x, y, z, w). P carries a uniform scale s, so P * S_j = (rigid) * s on the rest
// vertex; the kernels scale the rest vertex (or its offset from the centre) by s before the rigid transform.
using JointDq = float[8];

// A rotation matrix from a blended, not yet normalised quaternion: R(q) / |q|^2 written with 2 / |q|^2, so the
// normalisation costs one division and no square root. `half_norm2` is |q|^2 / 2 (half_norm2_of, or a cheaper
// form the caller knows). The epsilon keeps a (never expected) zero blend finite: the group's quaternions are
// sign-aligned with its first joint, so |blend| >= that joint's weight > 0.
struct Rot {
  float r00, r01, r02, r10, r11, r12, r20, r21, r22, s2;
};
[[gnu::always_inline]] inline float half_norm2_of(float qx, float qy, float qz, float qw) {
  return 0.5f * (qx * qx + qy * qy + qz * qz + qw * qw);
}
[[gnu::always_inline]] inline Rot rotation_of(float qx, float qy, float qz, float qw, float half_norm2) {
  const float s2 = 1.0f / (half_norm2 + 1e-30f);
  const float xs = qx * s2, ys = qy * s2, zs = qz * s2;
  const float xx = qx * xs, yy = qy * ys, zz = qz * zs, xy = qx * ys, xz = qx * zs, yz = qy * zs;
  const float wx = qw * xs, wy = qw * ys, wz = qw * zs;
  return {1.0f - (yy + zz), xy - wz, xz + wy, xy + wz, 1.0f - (xx + zz), yz - wx, xz - wy, yz + wx, 1.0f - (xx + yy),
          s2};
}

// Half the squared length of a two-joint group's blend q0 + w (q1 - q0), per vertex: a quadratic in the one weight
// with the group's coefficients, two multiply-adds where the sum of squares of the blended components takes four
// and the 2 / |q|^2 another multiply. The loops are bound by their multiplies and FMAs (one 512-bit one a cycle on
// Zen 4), so cor's two-influence loop loses 3 of its 69.
struct HalfNorm2 {
  float c0 = 0.0f, c1 = 0.0f, c2 = 0.0f;  // |q0|^2 / 2, q0 . dq, |dq|^2 / 2
  static HalfNorm2 of(const float* q0, const float* dq) {
    HalfNorm2 h;
    for (int c = 0; c < 4; ++c) {
      h.c0 += 0.5f * q0[c] * q0[c];
      h.c1 += q0[c] * dq[c];
      h.c2 += 0.5f * dq[c] * dq[c];
    }
    return h;
  }
  [[gnu::always_inline]] float at(float w) const { return c0 + w * (c1 + w * c2); }
};

// Dual quaternion skinning of one group (K >= 2): blend the K sign-aligned dual quaternions, normalise, and
// apply the rigid transform to s * rest position; the normal turns by the rotation alone (already unit, no
// renormalisation). Same loop shape as skin_group, for the same vectoriser reasons.
template <int K, bool Muscle, bool Whole>
[[gnu::always_inline]] inline void dqs_group(const SkinLayout& L, std::uint32_t first, std::uint32_t count,
                                             const float (*d)[8], float scale, const float* __restrict force,
                                             float* __restrict ox, float* __restrict oy, float* __restrict oz,
                                             float* __restrict onx, float* __restrict ony, float* __restrict onz) {
  const float* __restrict px = column_at(L.px, first);
  const float* __restrict py = column_at(L.py, first);
  const float* __restrict pz = column_at(L.pz, first);
  const float* __restrict nx = column_at(L.nx, first);
  const float* __restrict ny = column_at(L.ny, first);
  const float* __restrict nz = column_at(L.nz, first);
  const float* __restrict w1 = column_at(L.weight[1], first);
  const float* __restrict w2 = column_at(L.weight[2], first);
  const float* __restrict w3 = column_at(L.weight[3], first);
  const std::int32_t* __restrict p0 = column_at(L.muscle_point[0], first);
  const std::int32_t* __restrict p1 = column_at(L.muscle_point[1], first);
  const std::int32_t* __restrict p2 = column_at(L.muscle_point[2], first);
  const float* __restrict c0 = column_at(L.muscle_coefficient[0], first);
  const float* __restrict c1 = column_at(L.muscle_coefficient[1], first);
  const float* __restrict c2 = column_at(L.muscle_coefficient[2], first);
  float D[K][8];  // differences from the first, as in skin_group
  for (int k = 0; k < K; ++k)
    for (int c = 0; c < 8; ++c) D[k][c] = k == 0 ? d[0][c] : d[k][c] - d[0][c];
  const HalfNorm2 half = K == 2 ? HalfNorm2::of(D[0], D[1]) : HalfNorm2{};
  ox += first, oy += first, oz += first, onx += first, ony += first, onz += first;
  const std::size_t n = whole_vectors<Whole>(count);
  for (std::size_t i = 0; i < n; ++i) {
    float v1 = 0.0f, v2 = 0.0f, v3 = 0.0f;
    if constexpr (K > 1) v1 = w1[i];
    if constexpr (K > 2) v2 = w2[i];
    if constexpr (K > 3) v3 = w3[i];
    auto blend = [&](int c) {
      float r = D[0][c];
      if constexpr (K > 1) r += v1 * D[1][c];
      if constexpr (K > 2) r += v2 * D[2][c];
      if constexpr (K > 3) r += v3 * D[3][c];
      return r;
    };
    const float qx = blend(0), qy = blend(1), qz = blend(2), qw = blend(3);
    const float ex = blend(4), ey = blend(5), ez = blend(6), ew = blend(7);
    const Rot R = rotation_of(qx, qy, qz, qw, K == 2 ? half.at(v1) : half_norm2_of(qx, qy, qz, qw));
    // Translation 2 (e q*)_xyz / |q|^2 of the normalised blend (Kavan et al.'s formula).
    const float tx = R.s2 * (qw * ex - ew * qx + qy * ez - qz * ey);
    const float ty = R.s2 * (qw * ey - ew * qy + qz * ex - qx * ez);
    const float tz = R.s2 * (qw * ez - ew * qz + qx * ey - qy * ex);
    const float a = nx[i], c = ny[i], e = nz[i];
    const float ux = R.r00 * a + R.r01 * c + R.r02 * e;
    const float uy = R.r10 * a + R.r11 * c + R.r12 * e;
    const float uz = R.r20 * a + R.r21 * c + R.r22 * e;
    onx[i] = ux;
    ony[i] = uy;
    onz[i] = uz;
    const float x = scale * px[i], y = scale * py[i], z = scale * pz[i];
    float sx = R.r00 * x + R.r01 * y + R.r02 * z + tx;
    float sy = R.r10 * x + R.r11 * y + R.r12 * z + ty;
    float sz = R.r20 * x + R.r21 * y + R.r22 * z + tz;
    if constexpr (Muscle) {
      const float disp = c0[i] * force[p0[i]] + c1[i] * force[p1[i]] + c2[i] * force[p2[i]];
      sx += disp * ux;
      sy += disp * uy;
      sz += disp * uz;
    }
    ox[i] = sx;
    oy[i] = sy;
    oz[i] = sz;
  }
}

// Optimised centres of rotation (Le & Hodgins 2016) of one group (K >= 2): the blended matrices place the
// vertex's centre c (linear blending is exact enough there: c sits where the weights say the joint is), the
// blended quaternion R turns the rest offset about it: v' = R s (v - c) + LBS(c). The normal turns by R.
template <int K, bool Muscle, bool Whole>
[[gnu::always_inline]] inline void cor_group(const SkinLayout& L, std::uint32_t first, std::uint32_t count,
                                             const float (*m)[12], const float (*d)[8], float scale,
                                             const float* __restrict force, float* __restrict ox,
                                             float* __restrict oy, float* __restrict oz, float* __restrict onx,
                                             float* __restrict ony, float* __restrict onz) {
  const float* __restrict px = column_at(L.px, first);
  const float* __restrict py = column_at(L.py, first);
  const float* __restrict pz = column_at(L.pz, first);
  const float* __restrict nx = column_at(L.nx, first);
  const float* __restrict ny = column_at(L.ny, first);
  const float* __restrict nz = column_at(L.nz, first);
  const float* __restrict cxs = column_at(L.cx, first);
  const float* __restrict cys = column_at(L.cy, first);
  const float* __restrict czs = column_at(L.cz, first);
  const float* __restrict w1 = column_at(L.weight[1], first);
  const float* __restrict w2 = column_at(L.weight[2], first);
  const float* __restrict w3 = column_at(L.weight[3], first);
  const std::int32_t* __restrict p0 = column_at(L.muscle_point[0], first);
  const std::int32_t* __restrict p1 = column_at(L.muscle_point[1], first);
  const std::int32_t* __restrict p2 = column_at(L.muscle_point[2], first);
  const float* __restrict c0 = column_at(L.muscle_coefficient[0], first);
  const float* __restrict c1 = column_at(L.muscle_coefficient[1], first);
  const float* __restrict c2 = column_at(L.muscle_coefficient[2], first);
  float M[K][12], Q[K][4];  // differences from the first, as in skin_group
  for (int k = 0; k < K; ++k) {
    for (int c = 0; c < 12; ++c) M[k][c] = k == 0 ? m[0][c] : m[k][c] - m[0][c];
    for (int c = 0; c < 4; ++c) Q[k][c] = k == 0 ? d[0][c] : d[k][c] - d[0][c];
  }
  const HalfNorm2 half = K == 2 ? HalfNorm2::of(Q[0], Q[1]) : HalfNorm2{};
  ox += first, oy += first, oz += first, onx += first, ony += first, onz += first;
  const std::size_t n = whole_vectors<Whole>(count);
  for (std::size_t i = 0; i < n; ++i) {
    float v1 = 0.0f, v2 = 0.0f, v3 = 0.0f;
    if constexpr (K > 1) v1 = w1[i];
    if constexpr (K > 2) v2 = w2[i];
    if constexpr (K > 3) v3 = w3[i];
    auto blend = [&](int c) {
      float r = M[0][c];
      if constexpr (K > 1) r += v1 * M[1][c];
      if constexpr (K > 2) r += v2 * M[2][c];
      if constexpr (K > 3) r += v3 * M[3][c];
      return r;
    };
    auto qblend = [&](int c) {
      float r = Q[0][c];
      if constexpr (K > 1) r += v1 * Q[1][c];
      if constexpr (K > 2) r += v2 * Q[2][c];
      if constexpr (K > 3) r += v3 * Q[3][c];
      return r;
    };
    const float b0 = blend(0), b1 = blend(1), b2 = blend(2), b3 = blend(3), b4 = blend(4), b5 = blend(5);
    const float b6 = blend(6), b7 = blend(7), b8 = blend(8), b9 = blend(9), b10 = blend(10), b11 = blend(11);
    const float cx = cxs[i], cy = cys[i], cz = czs[i];
    const float lx = b0 * cx + b3 * cy + b6 * cz + b9;
    const float ly = b1 * cx + b4 * cy + b7 * cz + b10;
    const float lz = b2 * cx + b5 * cy + b8 * cz + b11;
    const float qx = qblend(0), qy = qblend(1), qz = qblend(2), qw = qblend(3);
    const Rot R = rotation_of(qx, qy, qz, qw, K == 2 ? half.at(v1) : half_norm2_of(qx, qy, qz, qw));
    const float a = nx[i], c = ny[i], e = nz[i];
    const float ux = R.r00 * a + R.r01 * c + R.r02 * e;
    const float uy = R.r10 * a + R.r11 * c + R.r12 * e;
    const float uz = R.r20 * a + R.r21 * c + R.r22 * e;
    onx[i] = ux;
    ony[i] = uy;
    onz[i] = uz;
    const float x = scale * (px[i] - cx), y = scale * (py[i] - cy), z = scale * (pz[i] - cz);
    float sx = R.r00 * x + R.r01 * y + R.r02 * z + lx;
    float sy = R.r10 * x + R.r11 * y + R.r12 * z + ly;
    float sz = R.r20 * x + R.r21 * y + R.r22 * z + lz;
    if constexpr (Muscle) {
      const float disp = c0[i] * force[p0[i]] + c1[i] * force[p1[i]] + c2[i] * force[p2[i]];
      sx += disp * ux;
      sy += disp * uy;
      sz += disp * uz;
    }
    ox[i] = sx;
    oy[i] = sy;
    oz[i] = sz;
  }
}

// What one walker's kernel reads besides the layout: its world matrices, and for the non-linear modes its
// joints' dual quaternions and scale.
struct WalkerPose {
  const float (*world)[12] = nullptr;
  const float (*dq)[8] = nullptr;  // null in SkinningMode::Linear
  float scale = 1.0f;
  SkinningMode mode = SkinningMode::Linear;
  const float* force = nullptr;  // null: no muscle displacement
  // Per joint: 1 / the common length of its world 3x3's columns when they are orthogonal and of equal length (a
  // rotation times the walker's scale), else 0 (the normal is then renormalised per vertex).
  const float* normal_scale = nullptr;
};

template <bool Muscle, bool Whole>
[[gnu::always_inline]] inline void dispatch(const SkinLayout& L, const SkinGroup& g, std::uint32_t first,
                                            std::uint32_t count, const WalkerPose& p,
                                            const float (*m)[12], const float (*d)[8], float* ox, float* oy,
                                            float* oz, float* onx, float* ony, float* onz) {
  const float* force = p.force;
  // One influence is a rigid transform whatever the mode: the linear body is exact and the cheapest.
  if (g.influences <= 1 || p.mode == SkinningMode::Linear) {
    const float ns = p.normal_scale[g.joints[0]];
    switch (g.influences) {
      case 1:
        if (ns > 0.0f)
          skin_group<1, Muscle, Whole, true>(L, first, count, m, force, ox, oy, oz, onx, ony, onz, ns);
        else
          skin_group<1, Muscle, Whole>(L, first, count, m, force, ox, oy, oz, onx, ony, onz);
        break;
      case 2: skin_group<2, Muscle, Whole>(L, first, count, m, force, ox, oy, oz, onx, ony, onz); break;
      case 3: skin_group<3, Muscle, Whole>(L, first, count, m, force, ox, oy, oz, onx, ony, onz); break;
      default: skin_group<4, Muscle, Whole>(L, first, count, m, force, ox, oy, oz, onx, ony, onz); break;
    }
  } else if (p.mode == SkinningMode::DualQuaternion) {
    switch (g.influences) {
      case 2: dqs_group<2, Muscle, Whole>(L, first, count, d, p.scale, force, ox, oy, oz, onx, ony, onz); break;
      case 3: dqs_group<3, Muscle, Whole>(L, first, count, d, p.scale, force, ox, oy, oz, onx, ony, onz); break;
      default: dqs_group<4, Muscle, Whole>(L, first, count, d, p.scale, force, ox, oy, oz, onx, ony, onz); break;
    }
  } else {
    switch (g.influences) {
      case 2: cor_group<2, Muscle, Whole>(L, first, count, m, d, p.scale, force, ox, oy, oz, onx, ony, onz); break;
      case 3: cor_group<3, Muscle, Whole>(L, first, count, m, d, p.scale, force, ox, oy, oz, onx, ony, onz); break;
      default: cor_group<4, Muscle, Whole>(L, first, count, m, d, p.scale, force, ox, oy, oz, onx, ony, onz); break;
    }
  }
}

template <bool Whole>
[[gnu::always_inline]] inline void run_group(bool muscle, const SkinLayout& L, const SkinGroup& g, std::uint32_t first,
                                             std::uint32_t count, const WalkerPose& p, const float (*m)[12],
                                             const float (*d)[8], float* ox, float* oy, float* oz, float* onx,
                                             float* ony, float* onz) {
  if (muscle)
    dispatch<true, Whole>(L, g, first, count, p, m, d, ox, oy, oz, onx, ony, onz);
  else
    dispatch<false, Whole>(L, g, first, count, p, m, d, ox, oy, oz, onx, ony, onz);
}

// The same body three times: for x86-64-v4 (AVX-512 F/BW/DQ/VL, 16 lanes), x86-64-v3 (AVX2 + FMA + F16C + BMI:
// every x86 CPU since 2013-2015) and the baseline (SSE2). skin_group and its siblings are forced inline so each
// copy vectorises for its own ISA; a callee left out of line is compiled for the baseline only, which is what an
// earlier target_clones version silently did (463 M vertices/s at level 0, against about 1,000 M with the AVX2
// body inlined). The AVX-512 copy is the same SoA loop at 16 lanes (layout arrays are padded to 16 floats), not a
// hand-written intrinsics body: one source of truth that the tests hold to the twin on every CPU that runs it.
[[gnu::always_inline]] inline void skin_groups(const SkinLayout& L, const WalkerPose& p, float* ox, float* oy,
                                               float* oz, float* onx, float* ony, float* onz) {
  float m[kMaxInfluences][12];
  float d[kMaxInfluences][8];
  for (const SkinGroup& g : L.groups) {
    for (std::uint32_t k = 0; k < g.influences; ++k)
      for (int c = 0; c < 12; ++c) m[k][c] = p.world[g.joints[k]][c];
    if (p.mode != SkinningMode::Linear && g.influences > 1) {
      // Antipodality: q and -q are one rotation, but blending them cancels. Aligning every quaternion with the
      // group's first joint is per group, not per vertex, because a group's vertices share their joints.
      const float* q0 = p.dq[g.joints[0]];
      for (std::uint32_t k = 0; k < g.influences; ++k) {
        const float* q = p.dq[g.joints[k]];
        const float sign = q[0] * q0[0] + q[1] * q0[1] + q[2] * q0[2] + q[3] * q0[3] < 0.0f ? -1.0f : 1.0f;
        for (int c = 0; c < 8; ++c) d[k][c] = sign * q[c];
      }
    }
    // A group's vertices start anywhere in the layout's arrays, and a 16-float vector that straddles two cache
    // lines costs a split load or store: level 0's groups as they lie ran 8-15 % slower than the same groups
    // copied to 64-byte boundaries (every mode, AVX-512 and AVX2 bodies, AMD Zen 4). So a group of two vectors
    // or more is run as one unaligned block of 16 at its start, then whole aligned blocks, then one block of 16
    // ending at its end: the edge blocks overlap the middle, recomputing a few vertices (the same instructions
    // on the same inputs, so the same values), and no loop has a scalar remainder. Rejected: padding each group
    // to a 16-vertex boundary in the layout, which puts unused vertices between groups in every consumer's
    // arrays (renderer, subdivision cage, tests against the twin).
    const bool muscle = g.muscle && p.force;
    // (A function, not a lambda: a lambda's body is compiled for the baseline ISA, not the caller's target.)
    constexpr std::uint32_t lanes = kSimdLaneFloats;
    if (g.count < 2 * lanes) {
      run_group<false>(muscle, L, g, g.first, g.count, p, m, d, ox, oy, oz, onx, ony, onz);
      continue;
    }
    const std::uint32_t end = g.first + g.count;
    const std::uint32_t aligned = (g.first + lanes - 1) / lanes * lanes;
    const std::uint32_t middle = (end - aligned) / lanes * lanes;  // >= 16: the group holds two vectors or more
    // One call site, so the kernel is inlined once more rather than three times (compile time, code size).
    const std::uint32_t starts[3] = {g.first, aligned, end - lanes};
    const std::uint32_t counts[3] = {aligned != g.first ? lanes : 0, middle, aligned + middle != end ? lanes : 0};
    for (int s = 0; s < 3; ++s)
      if (counts[s] > 0) run_group<true>(muscle, L, g, starts[s], counts[s], p, m, d, ox, oy, oz, onx, ony, onz);
  }
}

// GCC needs prefer-vector-width=512 in the attribute or it keeps 256-bit vectors on x86-64-v4; clang's target
// attribute rejects that key and would then drop the whole attribute (its preference is a command-line flag only).
#if defined(__clang__)
#define STRATA_TARGET_AVX512 gnu::target("arch=x86-64-v4")
#else
#define STRATA_TARGET_AVX512 gnu::target("arch=x86-64-v4,prefer-vector-width=512")
#endif
[[STRATA_TARGET_AVX512]] void skin_groups_avx512(const SkinLayout& L, const WalkerPose& p, float* ox, float* oy,
                                                 float* oz, float* onx, float* ony, float* onz) {
  skin_groups(L, p, ox, oy, oz, onx, ony, onz);
}

[[gnu::target("arch=x86-64-v3")]] void skin_groups_avx2(const SkinLayout& L, const WalkerPose& p, float* ox,
                                                        float* oy, float* oz, float* onx, float* ony, float* onz) {
  skin_groups(L, p, ox, oy, oz, onx, ony, onz);
}

void skin_groups_portable(const SkinLayout& L, const WalkerPose& p, float* ox, float* oy, float* oz, float* onx,
                          float* ony, float* onz) {
  skin_groups(L, p, ox, oy, oz, onx, ony, onz);
}

// The unit quaternion (x, y, z, w) of a rotation matrix given as three columns (Shepperd's method: take the
// largest of the four diagonal combinations as the pivot, so no square root of a near-zero sum). A matrix that
// is not a rotation (a zero skinning matrix) yields the identity rather than NaN. (This file is built with fast
// math, so the isfinite below may fold away: the length test is what guards the zero case.)
void quaternion_of(const float* c0, const float* c1, const float* c2, float q[4]) {
  const float m00 = c0[0], m10 = c0[1], m20 = c0[2], m01 = c1[0], m11 = c1[1], m21 = c1[2];
  const float m02 = c2[0], m12 = c2[1], m22 = c2[2];
  const float tr = m00 + m11 + m22;
  float x, y, z, w;
  if (tr > m00 && tr > m11 && tr > m22) {
    w = 1.0f + tr;
    x = m21 - m12, y = m02 - m20, z = m10 - m01;
  } else if (m00 >= m11 && m00 >= m22) {
    x = 1.0f + m00 - m11 - m22;
    w = m21 - m12, y = m01 + m10, z = m02 + m20;
  } else if (m11 >= m22) {
    y = 1.0f + m11 - m00 - m22;
    w = m02 - m20, x = m01 + m10, z = m12 + m21;
  } else {
    z = 1.0f + m22 - m00 - m11;
    w = m10 - m01, x = m02 + m20, y = m12 + m21;
  }
  const float len2 = x * x + y * y + z * z + w * w;
  if (!(len2 > 1e-20f) || !std::isfinite(len2)) {
    q[0] = q[1] = q[2] = 0.0f, q[3] = 1.0f;
    return;
  }
  const float inv = 1.0f / std::sqrt(len2);
  q[0] = x * inv, q[1] = y * inv, q[2] = z * inv, q[3] = w * inv;
}

bool cpu_has_avx2_fma() {
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  return has;
}

bool cpu_has_avx512() {
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
           __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") && cpu_has_avx2_fma();
  }();
  return has;
}

std::atomic<SkinKernelIsa> g_forced{SkinKernelIsa::Auto};

// placement_of (components/walker.h) over a view; the same expressions, so the same bits.
Placement placement_at(const ColumnView<const float>& placement, std::size_t walker) {
  const float heading = placement.at(3, walker);
  return {{placement.at(0, walker), placement.at(1, walker), placement.at(2, walker)},
          std::cos(heading), std::sin(heading), placement.at(4, walker)};
}

}  // namespace

bool skin_columns_valid(const ColumnView<const float>& skinning, const ColumnView<const float>& placement,
                        const ColumnView<const float>& muscle_force) {
  const std::size_t n = skinning.count;
  if (skinning.components == 0 || skinning.components % kAffineFloats != 0 ||
      skinning.components / kAffineFloats > kMaxJointsPerRig || !skinning.fits(n, skinning.components) ||
      !placement.fits(n, 5))
    return false;
  if (muscle_force.components == 0) return true;
  return muscle_force.components >= 2 && muscle_force.components <= kMaxMusclePoints &&
         muscle_force.fits(n, muscle_force.components);
}

bool skin_layout_fits(const SkinLayout& layout, std::size_t joints, std::uint32_t muscle_points) {
  for (const SkinGroup& g : layout.groups) {
    if (g.influences < 1 || g.influences > kMaxInfluences || g.first + std::size_t(g.count) > layout.vertex_count)
      return false;
    for (std::uint32_t k = 0; k < g.influences; ++k)
      if (g.joints[k] < 0 || std::size_t(g.joints[k]) >= joints) return false;
  }
  if (layout.px.size() < layout.vertex_count) return false;
  return !(layout.muscle_points > 0 && muscle_points > 0 && layout.muscle_points > muscle_points);
}

namespace detail {

void skin_walker(const SkinLayout& layout, const ColumnView<const float>& skinning,
                 const ColumnView<const float>& placement, const ColumnView<const float>& muscle_force,
                 std::size_t w, const SkinOutput& out, SkinningMode mode) {
  const std::size_t joints = skinning.components / kAffineFloats;
  // The walker's skinning matrices with its placement folded in (world = P * S_j), so the kernel writes world space.
  const Placement P = placement_at(placement, w);
  float world[kMaxJointsPerRig][12];
  for (std::size_t j = 0; j < joints; ++j) {
    float s[12];
    for (int c = 0; c < 12; ++c) s[c] = skinning.base[(j * kAffineFloats + c) * skinning.stride + w];
    for (int col = 0; col < 4; ++col) {
      const glm::vec3 v{s[col * 3], s[col * 3 + 1], s[col * 3 + 2]};
      const glm::vec3 r = col < 3 ? P.direction(P.scale * v) : P.point(v);
      world[j][col * 3] = r.x;
      world[j][col * 3 + 1] = r.y;
      world[j][col * 3 + 2] = r.z;
    }
  }
  // Force factors times the walker's scale: the displacement is in humanoid metres, the output in world metres.
  float force[kMaxMusclePoints];
  const std::uint32_t points = muscle_force.components;
  const bool muscles = layout.muscle_points > 0 && points > 0;
  if (muscles)
    for (std::uint32_t p = 0; p < points; ++p) force[p] = P.scale * muscle_force.at(p, w);
  float normal_scale[kMaxJointsPerRig];
  for (std::size_t j = 0; j < joints; ++j) {
    const float* c = world[j];
    const float l0 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2], l1 = c[3] * c[3] + c[4] * c[4] + c[5] * c[5];
    const float l2 = c[6] * c[6] + c[7] * c[7] + c[8] * c[8];
    const float d01 = c[0] * c[3] + c[1] * c[4] + c[2] * c[5], d02 = c[0] * c[6] + c[1] * c[7] + c[2] * c[8];
    const float d12 = c[3] * c[6] + c[4] * c[7] + c[5] * c[8];
    // 1e-5 of the squared length: FK's float noise is far below it, a sheared or non-uniformly scaled joint far
    // above; the normal's length then errs by at most ~5e-6 against renormalising.
    const float tol = 1e-5f * l0;
    const bool similar = l0 > 1e-30f && l0 < 1e30f && std::abs(l1 - l0) <= tol && std::abs(l2 - l0) <= tol &&
                         std::abs(d01) <= tol && std::abs(d02) <= tol && std::abs(d12) <= tol;
    normal_scale[j] = similar ? 1.0f / std::sqrt(l0) : 0.0f;
  }
  WalkerPose pose;
  pose.world = world;
  pose.normal_scale = normal_scale;
  pose.force = muscles ? force : nullptr;
  pose.mode = mode;
  pose.scale = P.scale;
  float dq[kMaxJointsPerRig][8];
  if (mode != SkinningMode::Linear) {
    // The rigid part of each world matrix: rotation = its 3x3 / scale, translation = its fourth column.
    const float inv_scale = P.scale != 0.0f ? 1.0f / P.scale : 0.0f;
    for (std::size_t j = 0; j < joints; ++j) {
      float cols[9];
      for (int c = 0; c < 9; ++c) cols[c] = world[j][c] * inv_scale;
      float* q = dq[j];
      quaternion_of(cols, cols + 3, cols + 6, q);
      // Dual part 0.5 * (t, 0) * q.
      const float tx = world[j][9], ty = world[j][10], tz = world[j][11];
      q[4] = 0.5f * (tx * q[3] + ty * q[2] - tz * q[1]);
      q[5] = 0.5f * (-tx * q[2] + ty * q[3] + tz * q[0]);
      q[6] = 0.5f * (tx * q[1] - ty * q[0] + tz * q[3]);
      q[7] = -0.5f * (tx * q[0] + ty * q[1] + tz * q[2]);
    }
    pose.dq = dq;
  }
  switch (skin_kernel_isa()) {
    case SkinKernelIsa::Avx512:
      skin_groups_avx512(layout, pose, out.px, out.py, out.pz, out.nx, out.ny, out.nz);
      break;
    case SkinKernelIsa::Avx2Fma:
      skin_groups_avx2(layout, pose, out.px, out.py, out.pz, out.nx, out.ny, out.nz);
      break;
    default: skin_groups_portable(layout, pose, out.px, out.py, out.pz, out.nx, out.ny, out.nz); break;
  }
}

void apply_muscle_displacement(const MuscleDisplacementList& list, const ColumnView<const float>& placement,
                               const ColumnView<const float>& muscle_force, std::size_t w, const SkinOutput& out) {
  if (list.vertex.empty() || muscle_force.components == 0) return;
  const float scale = placement_at(placement, w).scale;
  for (std::size_t i = 0; i < list.vertex.size(); ++i) {
    float d = 0.0f;
    for (int k = 0; k < kMusclePointsPerVertex; ++k) d += list.coefficient[i][k] * muscle_force.at(list.point[i][k], w);
    d *= scale;
    const std::uint32_t v = list.vertex[i];
    out.px[v] += d * out.nx[v];
    out.py[v] += d * out.ny[v];
    out.pz[v] += d * out.nz[v];
  }
}

}  // namespace detail

bool skin_mode_fits(const SkinLayout& layout, SkinningMode mode) {
  if (mode == SkinningMode::CentresOfRotation) return layout.has_cor_centres();
  return mode == SkinningMode::Linear || mode == SkinningMode::DualQuaternion;
}

bool SkinWalkerJob::validate() const {
  if (!layout || !skin_columns_valid(skinning, placement, muscle_force)) return false;
  if (!skin_mode_fits(*layout, mode)) return false;
  if (!skin_layout_fits(*layout, skinning.components / kAffineFloats, muscle_force.components)) return false;
  return walker < skinning.count && out.holds(pad_to_lanes(layout->vertex_count));
}

bool SkinWalkerJob::run() const {
  if (!validate()) return false;
  detail::skin_walker(*layout, skinning, placement, muscle_force, walker, out, mode);
  return true;
}

bool MuscleDisplacementJob::validate() const {
  if (!list || list->point.size() != list->vertex.size() || list->coefficient.size() != list->vertex.size())
    return false;
  if (!placement.fits(placement.count, 5) || walker >= placement.count) return false;
  if (list->vertex.empty() || muscle_force.components == 0) return true;  // nothing to move
  if (!muscle_force.fits(placement.count, muscle_force.components)) return false;
  std::uint32_t top_vertex = 0;
  for (std::size_t i = 0; i < list->vertex.size(); ++i) {
    top_vertex = std::max(top_vertex, list->vertex[i]);
    for (const std::uint32_t p : list->point[i])
      if (p >= muscle_force.components) return false;
  }
  return out.holds(std::size_t(top_vertex) + 1);
}

bool MuscleDisplacementJob::run() const {
  if (!validate()) return false;
  detail::apply_muscle_displacement(*list, placement, muscle_force, walker, out);
  return true;
}

SkinColumns skin_columns(const SoaTable& walkers) {
  SkinColumns c{f32_view(walkers, kWalkerSkinning), f32_view(walkers, kWalkerPlacement),
                f32_view(walkers, kWalkerMuscleForce)};
  // A table made without muscles keeps one placeholder column (components/walker.h): no displacement.
  if (c.muscle_force.components < 2) c.muscle_force = {};
  return c;
}

SkinWalkerJob make_skin_walker_job(const SkinLayout& layout, const SoaTable& walkers, std::size_t walker,
                                   const SkinOutput& out, SkinningMode mode) {
  const SkinColumns c = skin_columns(walkers);
  return {&layout, c.skinning, c.placement, c.muscle_force, walker, out, mode};
}

MuscleDisplacementList make_muscle_displacement_list(const SkinLayout& layout, const MuscleBinding& binding,
                                                     std::span<const std::array<float, kMusclePointsPerVertex>> c) {
  if (c.size() != binding.size()) throw std::invalid_argument("make_muscle_displacement_list: one coefficient row per bound vertex");
  std::vector<std::uint32_t> rank(layout.vertex_count, 0xffffffffu);
  for (std::uint32_t i = 0; i < layout.vertex_count; ++i) rank[layout.original[i]] = i;
  MuscleDisplacementList list;
  for (std::size_t b = 0; b < binding.size(); ++b) {
    if (binding.vertex[b] >= rank.size()) throw std::invalid_argument("make_muscle_displacement_list: vertex out of range");
    list.vertex.push_back(rank[binding.vertex[b]]);
    list.point.push_back(binding.point[b]);
    list.coefficient.push_back(c[b]);
  }
  return list;
}

bool skin_kernel_isa_supported(SkinKernelIsa isa) {
  switch (isa) {
    case SkinKernelIsa::Avx512: return cpu_has_avx512();
    case SkinKernelIsa::Avx2Fma: return cpu_has_avx2_fma();
    default: return true;
  }
}

void force_skin_kernel_isa(SkinKernelIsa isa) {
  if (isa == SkinKernelIsa::Avx2Fma && !cpu_has_avx2_fma())
    throw std::invalid_argument("force_skin_kernel_isa: this CPU has no AVX2 + FMA");
  if (isa == SkinKernelIsa::Avx512 && !cpu_has_avx512())
    throw std::invalid_argument("force_skin_kernel_isa: this CPU has no AVX-512 (F, BW, DQ, VL)");
  g_forced.store(isa);
}

SkinKernelIsa skin_kernel_isa() {
  const SkinKernelIsa forced = g_forced.load(std::memory_order_relaxed);
  if (forced != SkinKernelIsa::Auto) return forced;
  if (cpu_has_avx512()) return SkinKernelIsa::Avx512;
  return cpu_has_avx2_fma() ? SkinKernelIsa::Avx2Fma : SkinKernelIsa::Portable;
}

const char* skin_kernel_isa_name(SkinKernelIsa isa) {
  switch (isa) {
    case SkinKernelIsa::Avx512: return "avx512";
    case SkinKernelIsa::Avx2Fma: return "avx2+fma";
    case SkinKernelIsa::Portable: return "sse2";
    default: return "auto";
  }
}

}  // namespace strata
