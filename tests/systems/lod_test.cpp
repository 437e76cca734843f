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
#include "scene/crowd.h"
#include "systems/lod.h"
#include "systems/pose_gather.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/state_hash.h"
#include "scene/step.h"

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
  EXPECT_EQ(lod_decide(v, p, {0, 0, 5}, 1.0f, 1.7f, kLodNoPrevious, -1, 3), -1) << "behind";
  EXPECT_EQ(lod_decide(v, p, {50, 0, -5}, 1.0f, 1.7f, kLodNoPrevious, -1, 3), -1) << "far to the side";
  EXPECT_EQ(lod_decide(v, p, {0, 0, -600}, 1.0f, 1.7f, kLodNoPrevious, -1, 3), -1) << "beyond the far plane";
  EXPECT_GE(lod_decide(v, p, {0, 0, -5}, 1.0f, 1.7f, kLodNoPrevious, -1, 3), 0) << "straight ahead";
  // A sphere straddling the edge of the view is kept.
  EXPECT_GE(lod_decide(v, p, {3.4f, 0, -5}, 1.0f, 1.7f, kLodNoPrevious, -1, 3), 0);
  // A fixed level applies to whatever is visible.
  EXPECT_EQ(lod_decide(v, p, {0, 0, -100}, 1.0f, 1.7f, kLodNoPrevious, 1, 3), 1);
}

TEST(LodDecide, CoarserWithDistanceAndStableAroundAThreshold) {
  const LodView v = camera_at_origin();
  const LodPolicy p;
  auto at = [&](float d, int previous) { return lod_decide(v, p, {0, 0, -d}, 1.0f, 1.7f, previous, -1, 3); };
  // 1.7 m is level0_px tall at focal * 1.7 / 360 m.
  const float d0 = v.focal_px * 1.7f / p.level0_px, d1 = v.focal_px * 1.7f / p.level1_px;
  EXPECT_EQ(at(0.5f * d0, kLodNoPrevious), 0);
  EXPECT_EQ(at(0.5f * (d0 + d1), kLodNoPrevious), 1);
  EXPECT_EQ(at(2.0f * d1, kLodNoPrevious), 2);
  // Walking back and forth across both thresholds without passing the hysteresis band changes nothing.
  int level = at(0.97f * d0, kLodNoPrevious);  // just inside level 0
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
std::unique_ptr<Crowd> staged_scene(DetailLevel level) {
  auto scene = std::make_unique<Crowd>(default_rig());
  for (float z : {-3.0f, -8.0f, -40.0f, 10.0f}) spawn_clip_walker(*scene, glm::vec3(0.0f, 0.0f, z), 0.0f, 0.0f, 1.0f, kRestPose);
  scene->motion.source = (MotionSource::Clip);
  set_detail_level(*scene, level);
  LodView v = camera_at_origin();
  // Camera 1 m up so the near walker is in view.
  const glm::mat4 projection = glm::perspective(glm::radians(60.0f), 1.0f, 0.1f, 500.0f);
  v.eye = glm::vec3(0.0f, 1.0f, 0.0f);
  v.view_projection = projection * glm::lookAt(v.eye, glm::vec3(0, 1, -1), glm::vec3(0, 1, 0));
  scene->lod.view = (v);
  return scene;
}

TEST(LodSystem, AutoSkinsEachVisibleWalkerAtItsLevelAndNothingCulled) {
  auto scene = staged_scene(DetailLevel::automatic());
  Profiler profiler(4, false);
  step(*scene, 0.0f, profiler);
  EXPECT_EQ(scene->lod.counts[0], 1u);
  EXPECT_EQ(scene->lod.counts[1], 1u);
  EXPECT_EQ(scene->lod.counts[2], 1u);
  EXPECT_EQ(scene->lod.counts[3], 1u) << "the walker behind the camera";
  // State is table membership: the k-th walker (nearest first) sits alone in level k's table, and its block of
  // that level's skinned storage lies around its ground position.
  const std::vector<Entity> walkers = scene->world.entities();
  ASSERT_EQ(walkers.size(), 4u);
  EXPECT_EQ(scene->slot_of(walkers[3]), DetailSlot::Culled);
  for (int k = 0; k < 3; ++k) {
    const DetailSlot slot = mesh_slot(k);
    EXPECT_EQ(scene->slot_of(walkers[static_cast<std::size_t>(k)]), slot) << "nearest walker, finest level";
    EXPECT_EQ(scene->table(slot).size(), 1u);
    const SkinnedCrowd& skinned = scene->skinned[slot_index(slot)];
    EXPECT_EQ(skinned.walkers, 1u);
    EXPECT_EQ(skinned.vertex_count, scene->rig().body->levels[static_cast<std::size_t>(k)].mesh.vertex_count());
    glm::vec3 lo, hi;
    ASSERT_TRUE(skinned.bounds(lo, hi));
    const float z = k == 0 ? -3.0f : k == 1 ? -8.0f : -40.0f;
    EXPECT_LT(lo.z, z);
    EXPECT_GT(hi.z, z);
  }
  EXPECT_TRUE(scene->world.validate().empty());
  // A fixed level still culls.
  auto fixed = staged_scene(DetailLevel::mesh(1));
  step(*fixed, 0.0f, profiler);
  EXPECT_EQ(fixed->lod.counts[1], 3u);
  EXPECT_EQ(fixed->lod.counts[3], 1u);
  EXPECT_EQ(current_skinned(*fixed).walkers, 3u);
}

// A walker's level of detail is the table it sits in: turning the camera away moves every walker to the culled
// table, turning it back moves them to their levels again, the world stays consistent through the swap-removes,
// and the determinism hash does not depend on the tables walkers passed through.
TEST(LodSystem, WalkersMoveBetweenTablesAsTheCameraTurns) {
  auto scene = staged_scene(DetailLevel::automatic());
  auto still = staged_scene(DetailLevel::automatic());
  Profiler profiler(4, false);
  step(*scene, 0.0f, profiler);
  step(*still, 0.0f, profiler);
  const LodView ahead = *scene->lod.view;
  LodView away = ahead;
  const glm::mat4 projection = glm::perspective(glm::radians(60.0f), 1.0f, 0.1f, 500.0f);
  away.view_projection = projection * glm::lookAt(away.eye, away.eye + glm::vec3(1, 0, 0), glm::vec3(0, 1, 0));
  scene->lod.view = away;
  const FrameProfile turned = step(*scene, 0.0f, profiler);
  EXPECT_EQ(turned.moved, 3u) << "the three visible walkers leave their level tables";
  EXPECT_EQ(scene->table(DetailSlot::Culled).size(), 4u);
  EXPECT_EQ(scene->lod.counts[3], 4u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(scene->skinned[static_cast<std::size_t>(k)].walkers, 0u);
  EXPECT_TRUE(scene->world.validate().empty());
  scene->lod.view = ahead;
  const FrameProfile back = step(*scene, 0.0f, profiler);
  EXPECT_EQ(back.moved, 3u);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(scene->table(mesh_slot(k)).size(), 1u);
  EXPECT_TRUE(scene->world.validate().empty());
  step(*still, 0.0f, profiler);
  step(*still, 0.0f, profiler);
  EXPECT_EQ(state_hash(*scene), state_hash(*still));
}

// Hysteresis across frames comes from the table: a walker just past the level-0 threshold stays at level 0 while
// it oscillates inside the band, and the stage moves nobody.
TEST(LodSystem, HysteresisKeepsTheTableAcrossFrames) {
  auto scene = std::make_unique<Crowd>(default_rig());
  const LodView v = camera_at_origin();
  const LodPolicy p;
  const float height = scene->skin.body_height;
  const float d0 = v.focal_px * height / p.level0_px;
  spawn_clip_walker(*scene, glm::vec3(0.0f, -1.0f, -0.9f * d0), 0.0f, 0.0f, 1.0f, kRestPose);
  set_detail_level(*scene, DetailLevel::automatic());
  scene->lod.view = v;
  Profiler profiler(4, false);
  step(*scene, 0.0f, profiler);
  const Entity walker = scene->world.entities().front();
  ASSERT_EQ(scene->slot_of(walker), DetailSlot::Mesh0);
  for (int i = 0; i < 6; ++i) {
    const float z = -(i % 2 ? 0.9f : 1.08f) * d0;  // across the threshold, inside the 15 % band
    const EntityLocation at = scene->world.location(walker);
    scene->world.table(at.table).f32(kWalkerPlacement, 2)[at.block] = z;
    const FrameProfile f = step(*scene, 0.0f, profiler);
    EXPECT_EQ(f.moved, 0u) << "frame " << i;
    EXPECT_EQ(scene->slot_of(walker), DetailSlot::Mesh0) << "frame " << i;
  }
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
  for (DetailLevel level : {DetailLevel::mesh(0), DetailLevel::mesh(1), DetailLevel::mesh(2), DetailLevel::automatic()}) {
    auto scene = staged_scene(level);
    step(*scene, 0.0f, profiler);
    std::vector<glm::vec3> joints;
    const std::size_t posed = gather_crowd_joints(*scene, joints);  // the culled fourth walker has none
    SkeletonDrawInput input{&scene->rig().skeleton, joints, posed};
    renderer.render(input, view, projection, body_draw_inputs(*scene));
    const std::size_t expected =
        level.is_automatic() ? triangles[0] + triangles[1] + triangles[2] : 3 * triangles[static_cast<std::size_t>(level.index())];
    EXPECT_EQ(renderer.triangles_drawn(), expected) << "level " << level.name();
  }
}

}  // namespace
}  // namespace strata
