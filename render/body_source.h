#pragma once
// What the body pass draws, as the renderer's one seam with whatever produces bodies. The pass reads a BodySource:
// a handful of batches per frame (one per body level in use), each a BodyBatch whose alternative says what it
// carries and therefore how the pass draws it. The pass never sees the scene, the systems or raw arrays passed
// alongside; the systems never see GL.
//
// Two kinds of batch today: BodyDrawInput, bodies skinned on the CPU (the skin system's output), six world-space
// SoA streams the pass uploads every frame and draws with one multi-draw per batch; and ImpostorBatch, far
// walkers drawn as one textured quad each from the rig's baked atlas (render/impostor_pass.h). CpuSkinnedBodies
// wraps CPU-skinned inputs alone; BodyBatches any mix, as render/scene_draw.h builds them from a Crowd.
//
// Adding a kind (the body pass is the one pass that changes; the systems, the skeleton and ground passes and the
// facade's callers do not):
//   1. Describe what it carries in a struct here and add it to BodyBatch. BodyPass::draw dispatches with
//      std::visit over an overload set with no catch-all, so the build fails until the pass handles the new kind;
//      a batch kind cannot be silently skipped.
//   2. Give BodyPass a program (its own vertex shader under render/shaders/, added to STRATA_EMBEDDED_FILES; the
//      fragment stage stays lit.frag, so every kind shades alike) and the GL objects the kind needs, and a
//      check in BodyPass::check so a malformed batch throws before the frame starts.
//   3. Write a BodySource that produces the batches (e.g. in render/scene_draw.cpp, from the Crowd).
// A GPU-skinned batch would carry the rest layout (components/skin_layout.h SkinLayout: rest positions and
// normals, each group's joints and weights, the triangles, and the muscle coefficients of a body with muscles),
// which the pass uploads once and keys by address as it keys index buffers by triangle list today; and, every
// frame, the walkers' skinning matrices (the walker table's `skinning` field, F(j) A(j)^-1, 12 floats per joint),
// placements and muscle forces, streamed into shader storage buffers for a vertex shader that blends them. The
// systems already compute all of these; only the scene would skip the skin system for those walkers.
//
// Costs: virtual calls per batch (the pass asks for each batch twice a frame, to check it and to draw it), never
// per walker or per vertex; a batch is a few pointers and sizes, copied by value. The rejected alternative, a
// virtual "draw yourself" on the source, would put GL calls in every source and spread the pass's state (VAOs,
// cached index buffers) across them.
#include <cstddef>
#include <cstdint>
#include <span>
#include <variant>

#include "components/impostor_atlas.h"

namespace strata {

// CPU-skinned bodies: per-walker deformed vertices already in world space, as six component arrays (SoA, the skin
// system's output), sharing one triangle list (every walker of a batch uses the same mesh level). Walker w's
// vertex v is element w * stride + v of each array. Drawn lit in the skin colour.
struct BodyDrawInput {
  std::span<const std::uint32_t> triangles;
  const float *px = nullptr, *py = nullptr, *pz = nullptr, *nx = nullptr, *ny = nullptr, *nz = nullptr;
  std::size_t stride = 0;        // >= vertex_count
  std::size_t vertex_count = 0;
  std::size_t walker_count = 0;
  // Optional per-vertex colours, indexed like the positions (walker_count * stride entries), each bytes R, G, B,
  // A in memory; A blends the colour over the skin colour (0 = plain skin). The binding editor shows weights so.
  const std::uint32_t* rgba = nullptr;
  // RenderQuality::High only, each optional. A key per walker (walker_count entries) choosing its colours
  // (render/appearance.h); without keys every walker gets the plain skin colour. The surface classes of each
  // vertex and its distance to their cut (rig/surface_material.h SurfaceClasses; vertex_count entries each,
  // shared by every walker); without them all is skin. Ambient occlusion per vertex in [0, 1] (vertex_count
  // entries, shared); without it none.
  const std::uint32_t* walker_keys = nullptr;
  std::span<const std::uint8_t> materials;
  std::span<const float> material_cut;
  std::span<const float> ambient_occlusion;
};

// Impostors (components/impostor_atlas.h): far walkers drawn as one camera-facing quad each from `atlas`, which the
// pass uploads once and keys by its address and key. Per walker: ground position, heading (rad about +Y), scale
// (stature / the rig's) and gait phase in [0, 1), each an array read at [w] (the impostor table's columns).
struct ImpostorBatch {
  const ImpostorAtlas* atlas = nullptr;
  const float *x = nullptr, *y = nullptr, *z = nullptr, *heading = nullptr, *scale = nullptr, *phase = nullptr;
  std::size_t walker_count = 0;
  // RenderQuality::High: a key per walker choosing its colours, as BodyDrawInput::walker_keys; optional.
  const std::uint32_t* walker_keys = nullptr;
};

// One draw's worth of bodies; the alternative held is the batch's kind (see the top of this file to add one).
using BodyBatch = std::variant<BodyDrawInput, ImpostorBatch>;

// Where the body pass gets its batches from, for one frame. Batches are drawn in order, each with its own cached
// topology (at most BodyPass::kMaxBatches, 4, per frame); the pointers they hold must stay valid until the
// render() call that reads them returns.
class BodySource {
 public:
  virtual ~BodySource() = default;
  virtual std::size_t batch_count() const = 0;
  virtual BodyBatch batch(std::size_t index) const = 0;
};

// Any batches, in the order given (render/scene_draw.h builds a crowd's: its mesh levels, then its impostors).
// Holds the span, not a copy.
class BodyBatches final : public BodySource {
 public:
  explicit BodyBatches(std::span<const BodyBatch> batches) : batches_(batches) {}
  std::size_t batch_count() const override { return batches_.size(); }
  BodyBatch batch(std::size_t index) const override { return batches_[index]; }

 private:
  std::span<const BodyBatch> batches_;
};

// The CPU-skinned bodies of a frame, one batch per input (body level). Holds the span, not a copy.
class CpuSkinnedBodies final : public BodySource {
 public:
  explicit CpuSkinnedBodies(std::span<const BodyDrawInput> levels) : levels_(levels) {}
  std::size_t batch_count() const override { return levels_.size(); }
  BodyBatch batch(std::size_t index) const override { return levels_[index]; }

 private:
  std::span<const BodyDrawInput> levels_;
};

}  // namespace strata
