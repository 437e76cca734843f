#pragma once
// The headless ray tracer (`--renderer embree`): a frame of CPU-skinned bodies, the scenario's props and the
// ground traced on Intel Embree 3, lit as RenderQuality::High lights the GL frame (render/shaders/shading.glsl:
// the sun with a shadow ray instead of a shadow map, the sky-and-ground ambient darkened by the per-vertex
// occlusion, the skin material, each walker's palette, ACES tone mapping, sRGB), one ray per pixel.
//
// Why a second renderer: docs/rendering.md measured the GL path on llvmpipe at 1.5 s for 100 level-0 walkers with
// shadows where a throwaway Embree test needed 115 ms; rasterising grows with the triangles, tracing with their
// logarithm. The viewer and every windowed use stay GL; CrowdRenderer switches to this for headless frames when
// RenderOptions::backend says so, so every command keeps its one render_frame().
//
// Per frame: each walker is one Embree triangle geometry (RTC_BUILD_QUALITY_REFIT) over its skinned vertices,
// copied interleaved, and its level's shared triangle list; the scene persists while the frame's structure does
// (levels, walker counts, strides, props), so a frame refits each walker's BVH and rebuilds only the top level
// over the walkers. Rays run in 8x8 tiles on oneTBB; every pixel is a pure function of the scene, so the image
// does not depend on the thread count. Rejected: one geometry per level holding all its walkers, rebuilt every
// frame (RTC_BUILD_QUALITY_LOW): 435 ms a frame for 25 level-0 walkers where the refit takes 21 ms.
//
// What it does not draw: impostor batches (throws: trace meshes, `--level 0|1|2`), skeletons, the binding
// editor's tints; one sample per pixel where GL resolves 4x MSAA.
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "render/body_source.h"
#include "render/props_pass.h"
#include "render/render_options.h"

namespace strata {

class Profiler;

class RayTracer {
 public:
  // Throws std::runtime_error with Embree's message when the device cannot be created.
  RayTracer();
  ~RayTracer();
  RayTracer(const RayTracer&) = delete;
  RayTracer& operator=(const RayTracer&) = delete;

  // Traces `bodies` (CPU-skinned batches; throws std::invalid_argument, before any work, for another kind), the
  // props last given to set_props, and the ground (its extent fitted to `ground_points` as the GL ground pass
  // fits it; none drawn when options.draw_ground is false) from `view`/`projection` into `rgba` (width x height,
  // RGBA8, top row first). Non-finite vertices are dropped with their triangles. `profiler` (optional) times
  // "bvh" and "trace".
  void render(const BodySource& bodies, std::span<const glm::vec3> ground_points, const glm::mat4& view,
              const glm::mat4& projection, const RenderOptions& options, int width, int height,
              std::vector<std::uint8_t>& rgba, Profiler* profiler = nullptr);

  // The scenario's props (render/props_pass.h), traced from now on; rebuilt only when `key` changes. Empty: none.
  void set_props(std::uint64_t key, std::span<const PropVertex> triangles);

  // Body triangles in the last frame's scene.
  std::size_t triangles_traced() const { return triangles_traced_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t triangles_traced_ = 0;
};

}  // namespace strata
