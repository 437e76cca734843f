#pragma once
// The crowd renderer: draws a frame of walkers (skinned bodies, skeletons, or both) over a ground plane into its
// own render target, for a window (blit), a PNG (read-back) or a benchmark (finish). A facade over the passes,
// each a small class owning its GL objects:
//   render/render_target.h   the 4x multisampled colour + depth framebuffer, resolve, read-back, blit
//   render/ground_pass.h     the grid-lined ground under the walkers
//   render/skeleton_pass.h   bones and joints, instanced
//   render/body_pass.h       the skinned bodies, read from a BodySource (render/body_source.h), and impostors
//                            (render/impostor_pass.h)
//   render/reference_pass.h  the render benchmark's raw-instancing reference
//   render/shadow_pass.h     the sun's shadow map and the lighting of RenderQuality::High
// Their shaders are the files under render/shaders/, embedded in the library. A frame draws ground, skeletons,
// then bodies, and resolves. The caller owns the GL context, which must be current for every call including the
// destructor.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "render/body_source.h"
#include "render/footprint.h"
#include "render/props_pass.h"
#include "render/render_options.h"
#include "render/skeleton_input.h"

namespace strata {

class Profiler;

class CrowdRenderer {
 public:
  // Needs a current GL 4.5 core context. Throws std::runtime_error on shader/FBO failure, std::invalid_argument
  // for a non-positive size (as do resize and, for too few joint positions, render).
  CrowdRenderer(int width, int height, RenderOptions options = {});
  ~CrowdRenderer();
  CrowdRenderer(const CrowdRenderer&) = delete;
  CrowdRenderer& operator=(const CrowdRenderer&) = delete;

  int width() const;
  int height() const;
  void resize(int width, int height);
  RenderOptions& options();
  // Times each pass of render() (shadow_map, ground, skeletons, bodies, resolve) under its own scope of
  // `profiler`, nested in whatever scope the caller has open, finishing each pass's GL work before its scope
  // closes. Null (the default) turns the timing off and with it those waits.
  void set_profiler(Profiler* profiler);

  // Draws one frame into the target: ground (when options().draw_ground), skeletons (when
  // options().draw_skeleton) and the bodies of `bodies`. Waits for nothing; read_rgba() or
  // blit_to_default_framebuffer() finish it. Throws std::invalid_argument, before drawing anything, when the
  // inputs' sizes disagree.
  void render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
              const BodySource& bodies);
  // The same with CPU-skinned bodies of one level, or none.
  void render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
              const BodyDrawInput* bodies = nullptr);
  // The same with CPU-skinned bodies at several levels (up to 4 draws, one per level; each keeps its own index
  // buffer).
  void render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
              std::span<const BodyDrawInput> body_levels);
  // Body triangles submitted by the last render() (walkers x triangles per level) or render_instanced_reference.
  std::size_t triangles_drawn() const;
  // Walkers drawn as impostors by the last render().
  std::size_t impostors_drawn() const;
  // The scenario's props (render/props_pass.h), drawn after the ground in every frame from now on; uploaded only
  // when `key` differs from the last. An empty list removes them.
  void set_props(std::uint64_t key, std::span<const PropVertex> triangles);
  std::uint64_t props_key() const;  // 0 when there are none
  // The render benchmark's reference (`strata bench --render`): walker 0 of `mesh` uploaded once as a static
  // mesh and drawn offsets.size() times in one glDrawElementsInstanced, each copy moved by its offset, into the
  // same target with the same material: raw instancing of the same triangles, with nothing streamed.
  void render_instanced_reference(const BodyDrawInput& mesh, std::span<const glm::vec3> offsets, const glm::mat4& view,
                                  const glm::mat4& projection);
  // The pixels the last render()'s walkers (bodies, skeletons, impostors) and their shadows can have changed
  // (render/footprint.h): outside it the frame holds only sky, ground and props. The whole frame after a
  // ray-traced frame or render_instanced_reference; empty when no walker was drawn.
  PixelRect last_footprint() const;
  // Waits until the GL has finished every command (for timing).
  void finish() const;
  // RGBA8 pixels, rows top to bottom (image order), width*height*4 bytes.
  void read_rgba(std::vector<std::uint8_t>& out) const;
  // The depth of each pixel of the last GL frame (render/render_target.h read_depth), rows as read_rgba's. Throws
  // std::logic_error after a ray-traced frame, which keeps no depth.
  void read_depth(std::vector<float>& out) const;
  // The single-sample framebuffer render() resolves into and read_rgba() reads: an overlay (the viewer's panel)
  // drawn into it after render() shows up in read_rgba().
  unsigned output_framebuffer() const;
  // Copies the target to framebuffer 0 (a window), scaled to the given size.
  void blit_to_default_framebuffer(int width, int height) const;

 private:
  // The passes live behind a pointer: callers (the commands, the viewer) see only what they hand in (the inputs,
  // the options), so a pass's members can change without rebuilding them.
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace strata
