// Keyframe sampling (X3D interpolator semantics) and the animation system's clock.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <glm/gtc/quaternion.hpp>

#include "io/hanim_loader.h"
#include "systems/animation_sample.h"
#include "scene/crowd.h"
#include "scene/spawn.h"
#include "scene/body_settings.h"
#include "scene/step.h"
#include "systems/mocap_drive.h"
#include "tests/systems/job_test_util.h"

namespace strata {
namespace {

float angle_about_x(const glm::quat& q) { return 2.0f * std::atan2(q.x, q.w); }

AnimationClip swing_clip() {
  AnimationClip clip;
  clip.name = "swing";
  clip.duration = 2.0f;
  RotationTrack r;
  r.joint = 1;
  r.times = {0.0f, 1.0f, 2.0f};
  r.values = {glm::angleAxis(0.0f, glm::vec3(1, 0, 0)), glm::angleAxis(0.8f, glm::vec3(1, 0, 0)),
              glm::angleAxis(0.0f, glm::vec3(1, 0, 0))};
  clip.rotations.push_back(r);
  TranslationTrack t;
  t.joint = 0;
  t.times = {0.0f, 2.0f};
  t.values = {glm::vec3(0.0f), glm::vec3(0.0f, -0.1f, 0.0f)};
  clip.translations.push_back(t);
  return clip;
}

TEST(SampleClip, InterpolatesRotationAndTranslation) {
  AnimationClip clip = swing_clip();
  std::vector<glm::quat> rot(3);
  glm::vec3 root;
  sample_clip(clip, 0.5f, rot, root);
  EXPECT_NEAR(angle_about_x(rot[1]), 0.4f, 1e-6f) << "slerp about a fixed axis is linear in angle";
  EXPECT_NEAR(root.y, -0.025f, 1e-7f);
  EXPECT_EQ(rot[0], glm::quat(1, 0, 0, 0)) << "joints without a track stay at identity";
  EXPECT_EQ(rot[2], glm::quat(1, 0, 0, 0));
  sample_clip(clip, 1.0f, rot, root);
  EXPECT_NEAR(angle_about_x(rot[1]), 0.8f, 1e-6f) << "exactly on a key";
}

TEST(SampleClip, LoopsWrapAndOneShotsClamp) {
  AnimationClip clip = swing_clip();
  std::vector<glm::quat> a(2), b(2);
  glm::vec3 ra, rb;
  sample_clip(clip, 0.3f, a, ra);
  sample_clip(clip, 4.3f, b, rb);
  EXPECT_NEAR(angle_about_x(a[1]), angle_about_x(b[1]), 1e-5f);
  sample_clip(clip, -1.7f, b, rb);
  EXPECT_NEAR(angle_about_x(a[1]), angle_about_x(b[1]), 1e-5f) << "negative times wrap too";
  clip.loop = false;
  sample_clip(clip, 5.0f, b, rb);
  EXPECT_NEAR(rb.y, -0.1f, 1e-7f) << "a one-shot clip holds its last key";
  sample_clip(clip, std::nanf(""), b, rb);
  EXPECT_TRUE(std::isfinite(rb.y)) << "a NaN time never reaches the pose";
}

TEST(SampleClip, TakesTheShorterArcBetweenAntipodalKeys) {
  AnimationClip clip;
  clip.duration = 1.0f;
  RotationTrack r;
  r.joint = 0;
  r.times = {0.0f, 1.0f};
  glm::quat q = glm::angleAxis(0.2f, glm::vec3(0, 1, 0));
  r.values = {q, -q};  // the same rotation, written with opposite sign
  clip.rotations.push_back(r);
  std::vector<glm::quat> rot(1);
  glm::vec3 root;
  sample_clip(clip, 0.5f, rot, root);
  EXPECT_NEAR(std::abs(glm::dot(rot[0], q)), 1.0f, 1e-6f);
}

TEST(AnimationSystem, AdvancesEachWalkerByItsRate) {
  Rig rig;
  rig.skeleton.joint_names = {"HumanoidRoot", "l_hip", "l_knee"};
  rig.skeleton.source_joint_names = rig.skeleton.joint_names;
  rig.skeleton.parents = {-1, 0, 1};
  rig.skeleton.centers = {{0, 1, 0}, {0.1f, 0.9f, 0}, {0.1f, 0.5f, 0}};
  rig.skeleton.limits.resize(3);
  rig.skeleton.stiffness.assign(3, glm::vec3(1.0f));
  rig.clips.push_back(swing_clip());
  Crowd scene(rig);
  spawn_clip_walker(scene, {0, 0, 0}, 0.0f, 0.0f, 1.0f, 0);
  spawn_clip_walker(scene, {1, 0, 0}, 0.0f, 0.0f, 0.5f, 0);
  spawn_clip_walker(scene, {2, 0, 0}, 0.0f, 0.0f, 1.0f, -1);
  Profiler profiler;
  for (int f = 0; f < 15; ++f) step(scene, 0.1f, profiler);  // 1.5 s
  WalkerLanes lanes = scene.lanes();
  auto joint1_angle = [&](std::size_t w) {
    glm::quat q(lanes.local_rotation[(1 * 4 + 3) * lanes.stride + w], lanes.local_rotation[(1 * 4 + 0) * lanes.stride + w],
                lanes.local_rotation[(1 * 4 + 1) * lanes.stride + w], lanes.local_rotation[(1 * 4 + 2) * lanes.stride + w]);
    return angle_about_x(q);
  };
  EXPECT_NEAR(joint1_angle(0), 0.4f, 1e-4f) << "t = 1.5 s: halfway back down";
  EXPECT_NEAR(joint1_angle(1), 0.6f, 1e-4f) << "half rate: t = 0.75 s";
  EXPECT_NEAR(joint1_angle(2), 0.0f, 1e-7f) << "clip -1 holds the rest pose";
  EXPECT_NEAR(lanes.root_translation[1 * lanes.stride + 0], -0.075f, 1e-5f);
  EXPECT_EQ(lanes.root_translation[1 * lanes.stride + 2], 0.0f);
}

TEST(AnimationSystem, AllClipsLayerEachOnItsOwnCycle) {
  Rig rig;
  rig.skeleton.joint_names = {"HumanoidRoot", "a", "b"};
  rig.skeleton.source_joint_names = rig.skeleton.joint_names;
  rig.skeleton.parents = {-1, 0, 0};
  rig.skeleton.centers = {{0, 1, 0}, {0.1f, 0.9f, 0}, {-0.1f, 0.9f, 0}};
  rig.skeleton.limits.resize(3);
  rig.skeleton.stiffness.assign(3, glm::vec3(1.0f));
  rig.clips.push_back(swing_clip());  // drives joint 1, 2 s cycle
  AnimationClip other;
  other.name = "other";
  other.duration = 0.5f;
  RotationTrack r;
  r.joint = 2;
  r.times = {0.0f, 0.5f};
  r.values = {glm::angleAxis(0.0f, glm::vec3(1, 0, 0)), glm::angleAxis(1.0f, glm::vec3(1, 0, 0))};
  other.rotations.push_back(r);
  rig.clips.push_back(other);
  Crowd scene(rig);
  spawn_clip_walker(scene, {0, 0, 0}, 0.0f, 0.0f, 1.0f, kAllClips);
  Profiler profiler;
  for (int f = 0; f < 7; ++f) step(scene, 0.1f, profiler);  // 0.7 s: clip 0 at 0.7 s, clip 1 at 0.2 s
  WalkerLanes lanes = scene.lanes();
  auto angle = [&](std::size_t j) {
    glm::quat q(lanes.local_rotation[(j * 4 + 3) * lanes.stride], lanes.local_rotation[(j * 4 + 0) * lanes.stride],
                lanes.local_rotation[(j * 4 + 1) * lanes.stride], lanes.local_rotation[(j * 4 + 2) * lanes.stride]);
    return angle_about_x(q);
  };
  EXPECT_NEAR(angle(1), 0.56f, 1e-4f);
  EXPECT_NEAR(angle(2), 0.4f, 1e-4f);
  EXPECT_NEAR(lanes.root_translation[lanes.stride], -0.035f, 1e-5f);
}

// validate() rejects each missing or mismatched input, and run() then writes nothing.
TEST(AnimationJob, JobValidity) {
  Rig rig;
  rig.skeleton.joint_names = {"HumanoidRoot", "l_hip", "l_knee"};
  rig.skeleton.source_joint_names = rig.skeleton.joint_names;
  rig.skeleton.parents = {-1, 0, 1};
  rig.skeleton.centers = {{0, 1, 0}, {0.1f, 0.9f, 0}, {0.1f, 0.5f, 0}};
  rig.skeleton.limits.resize(3);
  rig.skeleton.stiffness.assign(3, glm::vec3(1.0f));
  rig.clips.push_back(swing_clip());
  Crowd scene(rig);
  for (int w = 0; w < 3; ++w) spawn_clip_walker(scene, {0, 0, 0}, 0.0f, 0.1f * static_cast<float>(w), 1.0f, 0);
  SoaTable& table = scene.table(initial_slot(scene));
  const std::size_t written[] = {kWalkerClock, kWalkerLocalRotation, kWalkerRootTranslation};
  const AnimationJob good = make_animation_job(scene.rig(), table, 0.1f);
  for (std::size_t f : written) test::fill_sentinel(table, f);
  auto untouched = [&] {
    for (std::size_t f : written)
      if (!test::holds_sentinel(table, f)) return false;
    return true;
  };
  using namespace test;
  AnimationJob j = good;
  j.rig = nullptr;
  expect_refused(j, "no rig", untouched);
  j = good, j.dt = std::numeric_limits<float>::infinity();
  expect_refused(j, "dt not finite", untouched);
  j = good, j.clip = without_base(good.clip);
  expect_refused(j, "no clip selectors", untouched);
  j = good, j.rate = with_count(good.rate, 2);
  expect_refused(j, "rates of fewer walkers", untouched);
  j = good, j.time = with_components(good.time, 2);
  expect_refused(j, "time two columns wide", untouched);
  j = good, j.time = ColumnView<float>{const_cast<float*>(good.rate.base), 1, good.rate.stride, good.rate.count};
  expect_refused(j, "time written over the rates", untouched);
  j = good, j.local_rotation = with_components(good.local_rotation, 4 * 2);
  expect_refused(j, "rotations of another joint count", untouched);
  j = good, j.root_translation = with_stride(good.root_translation, 2);
  expect_refused(j, "root stride below the walker count", untouched);
  j = good, j.root_translation = good.local_rotation.columns(0, 3);
  expect_refused(j, "root translation over the rotations", untouched);

  EXPECT_TRUE(good.validate());
  EXPECT_TRUE(good.run());
  EXPECT_FALSE(test::holds_sentinel(table, kWalkerLocalRotation));
}

// The mocap drive job (the animation step of mocap walkers), the same checks.
TEST(MocapDriveJob, JobValidity) {
  const Rig rig = to_rig(load_default_humanoid());
  const AnimationClip clip = swing_clip();
  const FootContacts contacts;
  const MocapRig mocap = make_mocap_rig(rig.skeleton, clip, contacts);
  const auto joints = static_cast<std::uint32_t>(rig.skeleton.joint_count());
  auto table = make_walker_table("mocap", joints);
  for (std::uint32_t w = 0; w < 3; ++w) table->add(Entity{w + 1, 1});
  const std::size_t written[] = {kWalkerClock, kWalkerPlacement, kWalkerFootLock, kWalkerLocalRotation,
                                 kWalkerRootTranslation, kWalkerIkGoal, kWalkerIkMode};
  for (std::size_t f : written) test::fill_sentinel(*table, f);
  auto untouched = [&] {
    for (std::size_t f : written)
      if (!test::holds_sentinel(*table, f)) return false;
    return true;
  };
  using namespace test;
  const MocapDriveJob good = make_mocap_drive_job(mocap, *table, 1.0f / 60.0f);
  MocapDriveJob j = good;
  j.rig = nullptr;
  expect_refused(j, "no rig", untouched);
  MocapRig no_clip = mocap;
  no_clip.clip = nullptr;
  j = good, j.rig = &no_clip;
  expect_refused(j, "a rig without its clip", untouched);
  MocapRig legless = mocap;
  legless.limbs.clear();
  j = good, j.rig = &legless;
  expect_refused(j, "a rig without leg limbs", untouched);
  j = good, j.dt = std::numeric_limits<float>::quiet_NaN();
  expect_refused(j, "dt not finite", untouched);
  j = good, j.rate = without_base(good.rate);
  expect_refused(j, "no rates", untouched);
  j = good, j.placement = with_components(good.placement, 4);
  expect_refused(j, "placement without scale", untouched);
  j = good, j.foot_lock = with_count(good.foot_lock, 2);
  expect_refused(j, "foot locks of fewer walkers", untouched);
  j = good, j.local_rotation = with_components(good.local_rotation, 8);
  expect_refused(j, "rotations of another joint count", untouched);
  j = good, j.ik_goal = with_stride(good.ik_goal, 2);
  expect_refused(j, "goal stride below the walker count", untouched);
  j = good, j.ik_mode = with_components(good.ik_mode, 2);
  expect_refused(j, "modes for two limbs only", untouched);
  j = good, j.root_translation = good.placement.columns(0, 3);
  expect_refused(j, "root translation over the placement", untouched);

  EXPECT_TRUE(good.validate());
}

}  // namespace
}  // namespace strata
