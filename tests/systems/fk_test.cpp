// FK system (paper equations 1-3) against the recursive reference, on the shipped skeleton and random trees.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <tbb/global_control.h>

#include "components/walker.h"
#include "io/hanim_loader.h"
#include "systems/fk.h"
#include "reference/fk_reference.h"
#include "scene/crowd.h"
#include "scene/state_hash.h"
#include "scene/spawn.h"
#include "scene/step.h"
#include "tests/systems/job_test_util.h"

namespace strata {
namespace {

// Column-major 3x4 of walker w, joint j, from a matrix field base, as a glm::mat4.
glm::mat4 lane_matrix(const WalkerLanes& lanes, const float* base, std::size_t joint, std::size_t w) {
  glm::mat4 m(1.0f);
  for (int col = 0; col < 4; ++col)
    for (int row = 0; row < 3; ++row) m[col][row] = base[(joint * kAffineFloats + col * 3 + row) * lanes.stride + w];
  return m;
}

float max_abs_diff(const glm::mat4& a, const glm::mat4& b) {
  float d = 0.0f;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) d = std::max(d, std::abs(a[c][r] - b[c][r]));
  return d;
}

glm::quat random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<float> n(0.0f, 1.0f);
  glm::quat q(n(rng), n(rng), n(rng), n(rng));
  return glm::normalize(q);
}

// A random tree: joint j's parent is a random earlier joint, centres anywhere in a 2 m box.
Skeleton random_skeleton(std::mt19937_64& rng, std::size_t joints) {
  Skeleton s;
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (std::size_t j = 0; j < joints; ++j) {
    s.joint_names.push_back(std::string("j").append(std::to_string(j)));  // not "j" + ...: GCC 12 -Wrestrict false positive
    s.source_joint_names.push_back(s.joint_names.back());
    s.parents.push_back(j == 0 ? -1 : static_cast<int>(rng() % j));
    s.centers.push_back({u(rng), u(rng) + 1.0f, u(rng)});
    s.limits.emplace_back();
    s.stiffness.emplace_back(1.0f);
  }
  return s;
}

void write_pose(SoaTable& table, std::uint32_t block, const std::vector<glm::quat>& rotations, glm::vec3 root) {
  for (std::size_t j = 0; j < rotations.size(); ++j) {
    table.f32(kWalkerLocalRotation, j * 4 + 0)[block] = rotations[j].x;
    table.f32(kWalkerLocalRotation, j * 4 + 1)[block] = rotations[j].y;
    table.f32(kWalkerLocalRotation, j * 4 + 2)[block] = rotations[j].z;
    table.f32(kWalkerLocalRotation, j * 4 + 3)[block] = rotations[j].w;
  }
  for (int c = 0; c < 3; ++c) table.f32(kWalkerRootTranslation, c)[block] = root[c];
}

TEST(Fk, RestPoseGivesIdentitySkinningMatrices) {
  Rig rig;
  rig.skeleton = load_default_humanoid().skeleton;
  ASSERT_EQ(rig.skeleton.joint_count(), 25u);
  Crowd scene(rig);
  CrowdConfig config;
  config.motion = MotionSource::Clip;
  config.walkers = 20;
  config.clip = -1;
  spawn_crowd(scene, config);
  Profiler profiler;
  step(scene, 1.0f / 30.0f, profiler);
  WalkerLanes lanes = scene.lanes();
  for (std::size_t w = 0; w < lanes.count; ++w)
    for (std::size_t j = 0; j < lanes.joints; ++j) {
      EXPECT_EQ(lane_matrix(lanes, lanes.skinning, j, w), glm::mat4(1.0f))
          << "walker " << w << " joint " << rig.skeleton.joint_names[j] << ": exactly identity at rest";
      glm::mat4 world = lane_matrix(lanes, lanes.world, j, w);
      EXPECT_EQ(glm::vec3(world[3]), rig.skeleton.centers[j]) << "rest F(j) is A(j), the joint centre";
    }
}

TEST(Fk, ShoulderRotationMovesOnlyItsDescendantsAsTheReferenceDoes) {
  Skeleton skeleton = load_default_humanoid().skeleton;
  const int shoulder = skeleton.find_joint("l_shoulder");
  const int elbow = skeleton.find_joint("l_elbow");
  const int wrist = skeleton.find_joint("l_wrist");
  ASSERT_GE(shoulder, 0);
  ASSERT_GE(elbow, 0);
  ASSERT_GE(wrist, 0);
  std::vector<glm::quat> rotations(skeleton.joint_count(), glm::quat(1, 0, 0, 0));
  // -90 degrees about +X (the humanoid's left axis) swings the hanging arm forward, towards +Z (right-hand
  // rule: a positive rotation about +X turns -Y towards -Z, i.e. backwards).
  rotations[shoulder] = glm::angleAxis(-glm::half_pi<float>(), glm::vec3(1, 0, 0));

  auto table = make_walker_table("t", static_cast<std::uint32_t>(skeleton.joint_count()));
  table->add(Entity{1, 1});
  write_pose(*table, 0, rotations, glm::vec3(0.0f));
  ASSERT_TRUE(make_fk_job(skeleton, *table).run());
  WalkerLanes lanes = walker_lanes(*table, static_cast<std::uint32_t>(skeleton.joint_count()));
  ReferencePose ref = fk_reference(skeleton, rotations, glm::vec3(0.0f));

  const glm::vec3 cs = skeleton.centers[shoulder];
  for (int j : {elbow, wrist}) {
    glm::vec3 got = glm::vec3(lane_matrix(lanes, lanes.world, j, 0)[3]);
    glm::vec3 d = skeleton.centers[j] - cs;
    glm::vec3 expected = cs + glm::vec3(d.x, d.z, -d.y);  // Rx(-90): (x, y, z) -> (x, z, -y)
    EXPECT_LT(glm::length(got - expected), 1e-6f) << skeleton.joint_names[j];
    EXPECT_LT(glm::length(got - glm::vec3(ref.world[j][3])), 1e-6f);
    EXPECT_GT(got.z, skeleton.centers[j].z + 0.2f) << "the arm swings forward";
  }
  for (std::size_t j = 0; j < skeleton.joint_count(); ++j) {
    EXPECT_LT(max_abs_diff(lane_matrix(lanes, lanes.skinning, j, 0), ref.skinning[j]), 1e-6f)
        << skeleton.joint_names[j];
    bool descendant = false;
    for (int k = static_cast<int>(j); k >= 0; k = skeleton.parents[k]) descendant |= (k == shoulder);
    if (!descendant) {
      EXPECT_EQ(lane_matrix(lanes, lanes.skinning, j, 0), glm::mat4(1.0f))
          << skeleton.joint_names[j] << " is not below the shoulder and must not move at all";
    }
  }
}

TEST(Fk, RandomTreesAndPosesMatchRecursiveReference) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 4; ++trial) {
    Skeleton skeleton = random_skeleton(rng, 12 + 10 * trial);
    const std::size_t walkers = 37 + trial;  // not a multiple of the SIMD width: tails must be right
    auto table = make_walker_table("t", static_cast<std::uint32_t>(skeleton.joint_count()));
    std::vector<std::vector<glm::quat>> poses;
    std::vector<glm::vec3> roots;
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    for (std::size_t w = 0; w < walkers; ++w) {
      auto block = table->add(Entity{static_cast<std::uint32_t>(w + 1), 1});
      std::vector<glm::quat> pose;
      for (std::size_t j = 0; j < skeleton.joint_count(); ++j) pose.push_back(random_rotation(rng));
      glm::vec3 root(u(rng), u(rng), u(rng));
      write_pose(*table, block, pose, root);
      poses.push_back(pose);
      roots.push_back(root);
    }
    ASSERT_TRUE(make_fk_job(skeleton, *table).run());
    WalkerLanes lanes = walker_lanes(*table, static_cast<std::uint32_t>(skeleton.joint_count()));
    for (std::size_t w = 0; w < walkers; ++w) {
      ReferencePose ref = fk_reference(skeleton, poses[w], roots[w]);
      for (std::size_t j = 0; j < skeleton.joint_count(); ++j) {
        // Deep random chains accumulate float32 rounding; 1e-5 m over metre-sized links.
        ASSERT_LT(max_abs_diff(lane_matrix(lanes, lanes.skinning, j, w), ref.skinning[j]), 1e-5f)
            << "trial " << trial << " walker " << w << " joint " << j;
        ASSERT_LT(max_abs_diff(lane_matrix(lanes, lanes.world, j, w), ref.world[j]), 1e-5f);
      }
    }
  }
}

TEST(Fk, UnnormalisedAndZeroQuaternionsGiveRotationsNotNaN) {
  std::mt19937_64 rng(3);
  Skeleton skeleton = random_skeleton(rng, 6);
  auto table = make_walker_table("t", 6);
  table->add(Entity{1, 1});
  table->add(Entity{2, 1});
  std::vector<glm::quat> unit;
  for (int j = 0; j < 6; ++j) unit.push_back(random_rotation(rng));
  std::vector<glm::quat> scaled = unit;
  for (auto& q : scaled) q = q * 3.5f;
  write_pose(*table, 0, unit, glm::vec3(0.1f));
  write_pose(*table, 1, scaled, glm::vec3(0.1f));
  table->f32(kWalkerLocalRotation, 2 * 4 + 3)[1] = 0.0f;  // joint 2 of walker 1: zero quaternion
  for (int c = 0; c < 3; ++c) table->f32(kWalkerLocalRotation, 2 * 4 + c)[1] = 0.0f;
  ASSERT_TRUE(make_fk_job(skeleton, *table).run());
  WalkerLanes lanes = walker_lanes(*table, 6);
  for (std::size_t j = 0; j < 6; ++j) {
    glm::mat4 m = lane_matrix(lanes, lanes.skinning, j, 1);
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) ASSERT_TRUE(std::isfinite(m[c][r]));
  }
  // Joints 0 and 1 (never below joint 2, as parents precede children) match the unit-quaternion walker.
  for (std::size_t j = 0; j < 2; ++j)
    EXPECT_LT(max_abs_diff(lane_matrix(lanes, lanes.skinning, j, 0), lane_matrix(lanes, lanes.skinning, j, 1)), 1e-6f);
  // The zero quaternion acts as identity: joint 2's rotation equals its parent's.
  glm::mat4 m2 = lane_matrix(lanes, lanes.world, 2, 1);
  glm::mat4 mp = lane_matrix(lanes, lanes.world, static_cast<std::size_t>(skeleton.parents[2]), 1);
  EXPECT_LT(max_abs_diff(glm::mat4(glm::mat3(m2)), glm::mat4(glm::mat3(mp))), 1e-6f);
}

TEST(Fk, OutputIsIdenticalForOneAndTwoThreads) {
  const Rig rig = to_rig(load_default_humanoid());
  std::uint64_t hashes[2];
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Crowd scene(rig);
    CrowdConfig config;
    config.walkers = 1500;  // several 256-walker chunks, so the parallel path really splits
    config.motion = MotionSource::Clip;
    config.clip = rig.clips.empty() ? -1 : 0;
    spawn_crowd(scene, config);
    Profiler profiler;
    for (int f = 0; f < 5; ++f) step(scene, 1.0f / 30.0f, profiler);
    hashes[threads - 1] = state_hash(scene);
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

// validate() rejects each missing or mismatched input, and run() then writes nothing.
TEST(FkJob, JobValidity) {
  std::mt19937_64 rng(5);
  const Skeleton skeleton = random_skeleton(rng, 6);
  auto table = make_walker_table("t", 6);
  for (std::uint32_t w = 0; w < 3; ++w) table->add(Entity{w + 1, 1});
  for (std::uint32_t w = 0; w < 3; ++w) write_pose(*table, w, std::vector<glm::quat>(6, random_rotation(rng)), {});
  const FkJob good = make_fk_job(skeleton, *table);
  auto untouched = [&] {
    return test::holds_sentinel(*table, kWalkerWorld) && test::holds_sentinel(*table, kWalkerSkinning);
  };
  test::fill_sentinel(*table, kWalkerWorld);
  test::fill_sentinel(*table, kWalkerSkinning);
  using namespace test;
  FkJob j = good;
  j.skeleton = nullptr;
  expect_refused(j, "no skeleton", untouched);
  Skeleton cyclic = skeleton;
  cyclic.parents[2] = 4;  // a parent after its child: the chain would read an unwritten matrix
  j = good, j.skeleton = &cyclic;
  expect_refused(j, "parents not first", untouched);
  Skeleton short_centres = skeleton;
  short_centres.centers.pop_back();
  j = good, j.skeleton = &short_centres;
  expect_refused(j, "a centre missing", untouched);
  j = good, j.local_rotation = without_base(good.local_rotation);
  expect_refused(j, "no rotations", untouched);
  j = good, j.local_rotation = with_components(good.local_rotation, 5 * 4);
  expect_refused(j, "rotations of another joint count", untouched);
  j = good, j.root_translation = with_count(good.root_translation, 2);
  expect_refused(j, "root translation of fewer walkers", untouched);
  j = good, j.root_translation = with_stride(good.root_translation, 2);
  expect_refused(j, "stride below the walker count", untouched);
  j = good, j.world = without_base(good.world);
  expect_refused(j, "no world output", untouched);
  j = good, j.skinning = with_components(good.skinning, 6 * 12 - 1);
  expect_refused(j, "skinning output too narrow", untouched);
  j = good, j.world = good.skinning;
  expect_refused(j, "world and skinning outputs alias", untouched);
  // An input inside an output's memory: world over a scratch block whose upper columns hold the rotations.
  std::vector<float> block((6 * 12 + 6 * 4) * good.world.stride, 0.0f);
  j = good, j.world.base = block.data();
  j.local_rotation.base = block.data() + 6 * 8 * good.world.stride;
  expect_refused(j, "an output aliasing an input", untouched);

  EXPECT_TRUE(good.validate());
  EXPECT_TRUE(good.run());
  EXPECT_FALSE(test::holds_sentinel(*table, kWalkerWorld));
  // An empty table is valid and a no-op.
  auto empty = make_walker_table("e", 6);
  EXPECT_TRUE(make_fk_job(skeleton, *empty).run());
}

}  // namespace
}  // namespace strata
