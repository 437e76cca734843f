// Orbit camera. Convention (right-handed, +Y up, matching glm::lookAt / glm::perspective with depth -1..1):
//   eye = target + distance * (cos(pitch) * sin(yaw), sin(pitch), cos(pitch) * cos(yaw))
// so yaw 0, pitch 0 puts the eye on the +Z side of the target looking towards -Z, positive yaw swings the eye
// towards +X (a right-handed turn about +Y), positive pitch lifts it above the target. The up vector is +Y;
// pitch stays within (-1.5, 1.5) so the view direction never becomes parallel to it.
#include "render/camera.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>

namespace strata {

namespace {
constexpr float kPitchLimit = 1.5f;

float clamped_pitch(float pitch) { return std::clamp(pitch, -kPitchLimit, kPitchLimit); }
}  // namespace

glm::vec3 OrbitCamera::eye() const {
  const float p = clamped_pitch(pitch);
  const glm::vec3 offset{std::cos(p) * std::sin(yaw), std::sin(p), std::cos(p) * std::cos(yaw)};
  return target + distance * offset;
}

glm::mat4 OrbitCamera::view() const { return glm::lookAt(eye(), target, glm::vec3{0.0f, 1.0f, 0.0f}); }

glm::mat4 OrbitCamera::projection(float aspect) const {
  return glm::perspective(fov_y, aspect > 0.0f ? aspect : 1.0f, near_plane, far_plane);
}

void OrbitCamera::frame_box(const glm::vec3& box_min, const glm::vec3& box_max, float aspect) {
  // Fitting the bounding sphere rather than the eight corners keeps the framing independent of yaw and pitch,
  // so orbiting a framed crowd never clips it; the price is some empty border for flat boxes.
  target = 0.5f * (box_min + box_max);
  const float radius = std::max(0.5f * glm::length(box_max - box_min), 1e-3f);
  const float half_v = 0.5f * fov_y;
  const float half_h = std::atan(std::tan(half_v) * (aspect > 0.0f ? aspect : 1.0f));
  // A sphere of radius r seen from distance d subtends asin(r / d) each side of the axis.
  distance = radius / std::sin(std::min(half_v, half_h));
  far_plane = std::max(far_plane, distance + 2.0f * radius);
}

void OrbitCamera::frame_box_tight(const glm::vec3& box_min, const glm::vec3& box_max, float aspect, float margin) {
  target = 0.5f * (box_min + box_max);
  const float tan_v = std::tan(0.5f * fov_y);
  const float tan_h = tan_v * (aspect > 0.0f ? aspect : 1.0f);
  // Camera basis at the current yaw/pitch; the eye sits at target - forward * distance.
  const glm::vec3 offset = eye() - target;
  const glm::vec3 forward = -glm::normalize(offset);
  const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0.0f, 1.0f, 0.0f)));
  const glm::vec3 up = glm::cross(right, forward);
  // A corner at (x, y, z) in that basis relative to the target has depth distance + z and stays in view while
  // |x| <= (distance + z) tan_h and |y| <= (distance + z) tan_v: each corner gives a lower bound on distance.
  float needed = 1e-3f;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 corner{(i & 1) ? box_max.x : box_min.x, (i & 2) ? box_max.y : box_min.y,
                           (i & 4) ? box_max.z : box_min.z};
    const glm::vec3 d = corner - target;
    const float x = glm::dot(d, right), y = glm::dot(d, up), z = glm::dot(d, forward);
    needed = std::max({needed, margin * std::abs(x) / tan_h - z, margin * std::abs(y) / tan_v - z});
  }
  distance = needed;
  const float radius = 0.5f * glm::length(box_max - box_min);
  far_plane = std::max(far_plane, distance + 2.0f * radius);
  near_plane = std::min(near_plane, std::max(1e-3f, 0.5f * (distance - radius)));
}

void OrbitCamera::orbit(float dx_pixels, float dy_pixels, float viewport_height) {
  const float radians_per_pixel = glm::pi<float>() / std::max(viewport_height, 1.0f);
  yaw -= dx_pixels * radians_per_pixel;
  pitch = clamped_pitch(pitch + dy_pixels * radians_per_pixel);
}

void OrbitCamera::pan(float dx_pixels, float dy_pixels, float viewport_height) {
  const glm::mat4 v = view();
  const glm::vec3 right{v[0][0], v[1][0], v[2][0]};
  const glm::vec3 up{v[0][1], v[1][1], v[2][1]};
  const float metres_per_pixel = 2.0f * distance * std::tan(0.5f * fov_y) / std::max(viewport_height, 1.0f);
  target += metres_per_pixel * (-dx_pixels * right + dy_pixels * up);
}

void OrbitCamera::zoom(float wheel_steps) {
  distance = std::clamp(distance * std::pow(0.85f, wheel_steps), 1e-2f, 1e5f);
}

}  // namespace strata
