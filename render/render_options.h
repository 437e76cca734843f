#pragma once
// What the crowd renderer draws and in which colours; every pass reads its part of it at draw time, so a change
// (the viewer's panel toggles them) shows in the next frame.
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace strata {

// How much of the lighting a frame pays for. Low: one headlight, Lambert and a rim, colours written as they are
// (the renderer of the paper's reproduction, and what the crowd benchmarks time). High: the sun with a shadow map
// (walkers' shadows on the ground and on each other), a sky-and-ground ambient darkened by per-vertex ambient
// occlusion, a skin material (wrap lighting, subsurface tint, sheen), every walker dressed in its own colours
// (render/appearance.h), ACES tone mapping and sRGB output.
enum class RenderQuality { Low, High };

// Who draws a headless frame: the GL passes (every command and the viewer), or the Embree ray tracer
// (render/ray_tracer.h: skinned meshes, props and ground at RenderQuality::High's lighting, one ray per pixel;
// `--renderer embree` on crowd and bench). The viewer always draws with GL.
enum class RenderBackend { Gl, RayTraced };

struct RenderOptions {
  RenderQuality quality = RenderQuality::Low;
  RenderBackend backend = RenderBackend::Gl;
  // The sun of RenderQuality::High: towards it (world, normalised when used), an afternoon sun from behind the
  // default camera's left so that shadows fall towards the viewer's right, long enough to read at 45 degrees.
  glm::vec3 to_sun{-0.45f, 0.78f, 0.42f};
  bool draw_ground = true;
  bool draw_skeleton = true;           // bones and joints (drawn inside bodies when both are on)
  float bone_radius = 0.025f;          // metres at the parent end of a bone
  float joint_radius = 0.03f;          // metres
  glm::vec4 clear_color{0.62f, 0.70f, 0.80f, 1.0f};
  glm::vec3 bone_color{0.92f, 0.86f, 0.74f};
  glm::vec3 joint_color{0.80f, 0.25f, 0.20f};
  glm::vec3 skin_color{0.80f, 0.62f, 0.52f};
  glm::vec3 ground_color{0.50f, 0.52f, 0.49f};
};

}  // namespace strata
