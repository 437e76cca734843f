#pragma once
// The seam between a crowd scene and the renderer: what the body pass draws from the scene's last frame, the
// bounds a camera frames, and the level-of-detail view a camera gives the scene for the next frame.
#include <vector>

#include <glm/vec3.hpp>

#include "render/camera.h"
#include "render/body_source.h"
#include "scene/crowd_scene.h"

namespace strata {

// What the renderer needs to draw the scene's skinned bodies from the last simulate(): one input per body level
// in use (several under --level auto), empty when the scene has no body to draw.
std::vector<BodyDrawInput> body_draw_inputs(const CrowdScene& scene);
// Bounds of every skinned vertex drawn; false when none.
bool body_bounds(const CrowdScene& scene, glm::vec3& lo, glm::vec3& hi);
// The level-of-detail view (culling, projected sizes) of a camera rendering `viewport_height` pixels high.
LodView lod_view(const OrbitCamera& camera, float aspect, int viewport_height);


}  // namespace strata
