#include "render/scene_draw.h"

#include <cmath>

#include <glm/common.hpp>

namespace strata {

std::vector<BodyDrawInput> body_draw_inputs(const CrowdScene& scene) {
  std::vector<BodyDrawInput> inputs;
  for (const CrowdScene::BodyDraw& d : scene.body_draws()) {
    const SkinnedCrowd& s = *d.skinned;
    BodyDrawInput input;
    input.triangles = *d.triangles;
    input.px = s.px.data(), input.py = s.py.data(), input.pz = s.pz.data();
    input.nx = s.nx.data(), input.ny = s.ny.data(), input.nz = s.nz.data();
    input.stride = s.stride;
    input.vertex_count = s.vertex_count;
    input.walker_count = s.vertex_count ? s.walkers : 0;
    inputs.push_back(input);
  }
  return inputs;
}

bool body_bounds(const CrowdScene& scene, glm::vec3& lo, glm::vec3& hi) {
  bool any = false;
  for (const CrowdScene::BodyDraw& d : scene.body_draws()) {
    glm::vec3 a, b;
    if (!d.skinned->bounds(a, b)) continue;
    lo = any ? glm::min(lo, a) : a;
    hi = any ? glm::max(hi, b) : b;
    any = true;
  }
  return any;
}

LodView lod_view(const OrbitCamera& camera, float aspect, int viewport_height) {
  LodView v;
  v.view_projection = camera.projection(aspect) * camera.view();
  v.eye = camera.eye();
  v.focal_px = static_cast<float>(viewport_height) / (2.0f * std::tan(0.5f * camera.fov_y));
  return v;
}

}  // namespace strata
