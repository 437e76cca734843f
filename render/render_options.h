#pragma once
// What the crowd renderer draws and in which colours; every pass reads its part of it at draw time, so a change
// (the viewer's panel toggles them) shows in the next frame.
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

namespace strata {

struct RenderOptions {
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
