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
  // Frames an axis-aligned box (e.g. the crowd's bounds) at the current yaw/pitch: targets its centre and sets
  // the distance so its bounding sphere just fits the narrower of the vertical and horizontal fields of view
  // (far_plane grows if needed).
  void frame_box(const glm::vec3& box_min, const glm::vec3& box_max, float aspect);
  // Frames the box's eight corners at the current yaw and pitch as tightly as `margin` allows (1.0 = corners may
  // touch the image edge). For fixed shots such as `strata crowd`, where frame_box's sphere leaves the crowd
  // small in a wide frame; unlike frame_box the fit is only valid for this yaw and pitch.
  void frame_box_tight(const glm::vec3& box_min, const glm::vec3& box_max, float aspect, float margin = 1.08f);

  // Interactive controls for `strata view`, in window pixels (y down) so a drag feels the same at any size.
  // orbit: a drag across the full viewport height turns the camera by pi; dragging right moves the camera
  // left round the target (the scene follows the cursor), dragging down raises it.
  void orbit(float dx_pixels, float dy_pixels, float viewport_height);
  // pan: moves the target in the view plane so that a point at the target's depth follows the cursor.
  void pan(float dx_pixels, float dy_pixels, float viewport_height);
  // zoom: each wheel step (positive = towards the target) scales the distance by 0.85.
  void zoom(float wheel_steps);
};

}  // namespace strata
