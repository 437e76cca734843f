#pragma once
// Orbit camera shared by `strata crowd` (fixed framing) and `strata view` (mouse-driven orbit).
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace strata {

struct OrbitCamera {
  glm::vec3 target{0.0f, 0.9f, 0.0f};  // point orbited, world metres
  float distance = 4.0f;               // metres from target
  float yaw = 0.6f;                    // radians about +Y; 0 looks along -Z (from +Z towards the target)
  float pitch = 0.25f;                 // radians above the horizon, clamped to (-1.5, 1.5)
  float fov_y = 0.8f;                  // vertical field of view, radians
  float near_plane = 0.05f;
  float far_plane = 500.0f;

  glm::vec3 eye() const;
  glm::mat4 view() const;
  glm::mat4 projection(float aspect) const;
  // Frames an axis-aligned box (e.g. the crowd's bounds) so it fills most of the view at the current yaw/pitch.
  void frame_box(const glm::vec3& box_min, const glm::vec3& box_max, float aspect);
};

}  // namespace strata
