// Level of detail and culling: the per-walker decision (frustum, projected size, hysteresis), the frame script
// skinning each walker at its level and nothing it culls, and the renderer drawing exactly the triangles the
// chosen levels hold (real EGL context).
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/scene_setup.h"
#include "render/scene_draw.h"
#include "io/hanim_loader.h"
#include "render/gl_context.h"
#include "render/crowd_renderer.h"
#include "rig/body_rig.h"
#include "systems/animation_sample.h"
#include "scene/crowd_scene.h"
#include "systems/lod.h"
#include "systems/pose_gather.h"

namespace strata {
namespace {

// A camera at the origin looking down -Z, 60 degrees vertical field of view, 1000 px high.
LodView camera_at_origin() {
  LodView v;
  const glm::mat4 projection = glm::perspective(glm::radians(60.0f), 1.0f, 0.1f, 500.0f);
  v.view_projection = projection * glm::lookAt(glm::vec3(0.0f), glm::vec3(0, 0, -1), glm::vec3(0, 1, 0));
  v.eye = glm::vec3(0.0f);
  v.focal_px = 1000.0f / (2.0f * std::tan(glm::radians(30.0f)));
  return v;
}

TEST(LodDecide, CullsWhatTheCameraCannotSee) {
  const LodView v = camera_at_origin();
  const LodPolicy p;
  EXPECT_EQ(lod_decide(v, p, {0, 0, 5}, 1.0f, 1.7f, kLodUnset, -1, 3), -1) << "behind";
  EXPECT_EQ(lod_decide(v, p, {50, 0, -5}, 1.0f, 1.7f, kLodUnset, -1, 3), -1) << "far to the side";
  EXPECT_EQ(lod_decide(v, p, {0, 0, -600}, 1.0f, 1.7f, kLodUnset, -1, 3), -1) << "beyond the far plane";
  EXPECT_GE(lod_decide(v, p, {0, 0, -5}, 1.0f, 1.7f, kLodUnset, -1, 3), 0) << "straight ahead";
  // A sphere straddling the edge of the view is kept.
  EXPECT_GE(lod_decide(v, p, {3.4f, 0, -5}, 1.0f, 1.7f, kLodUnset, -1, 3), 0);
  // A fixed level applies to whatever is visible.
  EXPECT_EQ(lod_decide(v, p, {0, 0, -100}, 1.0f, 1.7f, kLodUnset, 1, 3), 1);
}

TEST(LodDecide, CoarserWithDistanceAndStableAroundAThreshold) {
  const LodView v = camera_at_origin();
  const LodPolicy p;
  auto at = [&](float d, int previous) { return lod_decide(v, p, {0, 0, -d}, 1.0f, 1.7f, previous, -1, 3); };
  // 1.7 m is level0_px tall at focal * 1.7 / 360 m.
  const float d0 = v.focal_px * 1.7f / p.level0_px, d1 = v.focal_px * 1.7f / p.level1_px;
  EXPECT_EQ(at(0.5f * d0, kLodUnset), 0);
  EXPECT_EQ(at(0.5f * (d0 + d1), kLodUnset), 1);
  EXPECT_EQ(at(2.0f * d1, kLodUnset), 2);
  // Walking back and forth across both thresholds without passing the hysteresis band changes nothing.
  int level = at(0.97f * d0, kLodUnset);  // just inside level 0
  ASSERT_EQ(level, 0);
  for (int i = 0; i < 20; ++i) {
    level = at(i % 2 ? 0.97f * d0 : 1.05f * d0, level);  // oscillate across the threshold, within 15 %
    EXPECT_EQ(level, 0) << "step " << i;
  }
  EXPECT_EQ(at(1.2f * d0, 0), 1) << "well past the band: coarser";
  EXPECT_EQ(at(0.97f * d0, 1), 1) << "back inside the band from level 1: stays";
  EXPECT_EQ(at(0.8f * d0, 1), 0) << "past the band: finer";
}

Rig default_rig() {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  return rig;
}

// Three walkers on a line away from a camera: near, middle and far; a fourth behind it.
std::unique_ptr<CrowdScene> staged_scene(int level) {
  auto scene = std::make_unique<CrowdScene>(default_rig());
  for (float z : {-3.0f, -8.0f, -40.0f, 10.0f}) scene->spawn(glm::vec3(0.0f, 0.0f, z), 0.0f, 0.0f, 1.0f, kRestPose);
  scene->set_motion(MotionSource::Clip);
  scene->set_body_level(level);
  LodView v = camera_at_origin();
  // Camera 1 m up so the near walker is in view.
  const glm::mat4 projection = glm::perspective(glm::radians(60.0f), 1.0f, 0.1f, 500.0f);
  v.eye = glm::vec3(0.0f, 1.0f, 0.0f);
  v.view_projection = projection * glm::lookAt(v.eye, glm::vec3(0, 1, -1), glm::vec3(0, 1, 0));
  scene->set_view(v);
  return scene;
}

TEST(LodSystem, AutoSkinsEachVisibleWalkerAtItsLevelAndNothingCulled) {
  auto scene = staged_scene(kAutoBodyLevel);
  Profiler profiler(4, false);
  scene->simulate(0.0f, profiler);
  EXPECT_EQ(scene->lod_counts()[0], 1u);
  EXPECT_EQ(scene->lod_counts()[1], 1u);
  EXPECT_EQ(scene->lod_counts()[2], 1u);
  EXPECT_EQ(scene->lod_counts()[3], 1u) << "the walker behind the camera";
  const auto draws = scene->body_draws();
  ASSERT_EQ(draws.size(), 3u);
  for (const auto& d : draws) {
    EXPECT_EQ(d.skinned->walkers, 1u);
    ASSERT_EQ(d.skinned->walker_ids.size(), 1u);
    EXPECT_EQ(d.skinned->walker_ids[0], static_cast<std::uint32_t>(d.level)) << "nearest walker, finest level";
    EXPECT_EQ(d.skinned->vertex_count, scene->rig().body->levels[static_cast<std::size_t>(d.level)].mesh.vertex_count());
    // The block really is that walker: its vertices lie around its ground position.
    glm::vec3 lo, hi;
    ASSERT_TRUE(d.skinned->bounds(lo, hi));
    const float z = d.level == 0 ? -3.0f : d.level == 1 ? -8.0f : -40.0f;
    EXPECT_LT(lo.z, z);
    EXPECT_GT(hi.z, z);
  }
  // A fixed level still culls.
  auto fixed = staged_scene(1);
  fixed->simulate(0.0f, profiler);
  EXPECT_EQ(fixed->lod_counts()[1], 3u);
  EXPECT_EQ(fixed->lod_counts()[3], 1u);
  EXPECT_EQ(fixed->skinned().walkers, 3u);
}

class LodRenderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    try {
      context_ = create_headless_gl_context();
    } catch (const std::exception& e) {
      GTEST_SKIP() << "no headless GL: " << e.what();
    }
  }
  std::unique_ptr<GlContext> context_;
};

// Forcing each level draws walkers x that level's triangles; auto draws each walker's own level's.
TEST_F(LodRenderTest, DrawnTriangleCountFollowsTheLevels) {
  CrowdRenderer renderer(160, 160);
  Profiler profiler(4, false);
  const glm::mat4 projection = glm::perspective(glm::radians(60.0f), 1.0f, 0.1f, 500.0f);
  const glm::mat4 view = glm::lookAt(glm::vec3(0, 1, 0), glm::vec3(0, 1, -1), glm::vec3(0, 1, 0));
  std::vector<std::size_t> triangles;
  for (const BodyLevel& level : default_bound_body()->levels) triangles.push_back(level.mesh.triangle_count());
  for (int level : {0, 1, 2, kAutoBodyLevel}) {
    auto scene = staged_scene(level);
    scene->simulate(0.0f, profiler);
    std::vector<glm::vec3> joints;
    gather_joint_positions(scene->lanes(), joints);
    SkeletonDrawInput input{&scene->rig().skeleton, joints, scene->walker_count()};
    renderer.render(input, view, projection, body_draw_inputs(*scene));
    const std::size_t expected =
        level == kAutoBodyLevel ? triangles[0] + triangles[1] + triangles[2] : 3 * triangles[static_cast<std::size_t>(level)];
    EXPECT_EQ(renderer.triangles_drawn(), expected) << "level " << body_level_name(level);
  }
}

}  // namespace
}  // namespace strata
