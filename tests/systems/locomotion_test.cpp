// The walk generator end to end: locomotion -> IK -> FK on the shipped skeleton, measured from the FK output.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include <tbb/global_control.h>

#include "io/hanim_loader.h"
#include "motion/gait.h"
#include "motion/track.h"
#include "scene/crowd.h"
#include "systems/gait_metrics.h"
#include "systems/pose_gather.h"
#include "scene/state_hash.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"
#include "tests/systems/job_test_util.h"

namespace strata {
namespace {

std::unique_ptr<Crowd> make_walkers(std::size_t n, std::uint64_t seed = 1) {
  auto crowd = std::make_unique<Crowd>(to_rig(load_default_humanoid()));
  Crowd& scene = *crowd;
  CrowdConfig config;
  config.motion = MotionSource::Walk;
  config.walkers = n;
  config.seed = seed;
  spawn_crowd(scene, config);
  return crowd;
}

TEST(Locomotion, CrowdMeetsTheGaitTargets) {
  std::unique_ptr<Crowd> crowd = make_walkers(9);
  Crowd& scene = *crowd;
  GaitMetrics metrics(scene.rig().skeleton, *scene.motion.locomotion.get(), scene.motion.style);
  Profiler profiler(120, false);
  const float dt = 1.0f / 60.0f;
  for (int f = 0; f < 600; ++f) {
    step(scene, dt, profiler);
    metrics.observe(scene.lanes(), scene.motion.paths, dt);
  }
  const GaitReport r = metrics.report();
  EXPECT_EQ(r.walkers, 9u);
  EXPECT_NEAR(r.seconds, 10.0, 1e-3);
  EXPECT_LT(r.foot_slide_mm_max, 1.0);
  EXPECT_LT(r.ik_position_error_max_m, 1e-5);
  EXPECT_EQ(r.limit_violations, 0u) << "worst " << r.limit_violation_max_rad << " rad";
  EXPECT_EQ(r.nan_count, 0u);
  EXPECT_GT(r.strides, 9u * 2u * 5u) << "every foot made several strides in 10 s";
  EXPECT_LT(r.stride_length_error_pct, 2.0);
  // Toe tip and heel clear the ground through the middle of every swing (GaitStyle::swing_clearance, guarded
  // between the swing's knots too; before, a slow walker's toe went 3-7 mm into the ground at mid-swing).
  EXPECT_GT(r.swing_clearance_min_mm, 3.0);
  EXPECT_GT(r.pelvis_bob_cm_mean, 1.0) << "the pelvis oscillates";
  EXPECT_LT(r.pelvis_bob_cm_mean, 12.0);
}

TEST(Locomotion, WalkerStaysOnItsPathAndFacesAlongIt) {
  std::unique_ptr<Crowd> crowd = make_walkers(4);
  Crowd& scene = *crowd;
  Profiler profiler(120, false);
  for (int f = 0; f < 200; ++f) {
    step(scene, 1.0f / 30.0f, profiler);
    WalkerLanes l = scene.lanes();
    for (std::size_t w = 0; w < l.count; ++w) {
      const CardinalSpline& path = scene.motion.paths[l.path[w]];
      const float s = l.gait[kGaitDistance * l.stride + w];
      const glm::vec3 on_path = path.point_at_length(s);
      const glm::vec3 placed{l.placement[0 * l.stride + w], 0.0f, l.placement[2 * l.stride + w]};
      ASSERT_LT(glm::length(on_path - placed), 1e-4f);
      const glm::vec3 t = path.tangent_at_length(s);
      const float h = l.placement[3 * l.stride + w];
      ASSERT_GT(t.x * std::sin(h) + t.z * std::cos(h), 0.9999f) << "heading follows the path tangent";
    }
  }
}

// Largest frame-to-frame change of the pelvis' vertical velocity (second difference of root height, metres per
// frame^2 at 60 fps) and largest per-frame joint displacement for one walker whose cadence target follows
// `targets` (switched at frames 150 and 400).
struct Smoothness {
  float root_second_difference = 0.0f;
  float joint_step = 0.0f;
  float final_cadence = 0.0f;
};

Smoothness walk_with_cadences(float c0, float c1, float c2) {
  Crowd scene(to_rig(load_default_humanoid()));
  set_paths(scene, make_stadium_lanes(glm::vec3(0.0f), 20.0f, 4.0f, 1, 1.0f));
  scene.motion.source = (MotionSource::Walk);
  spawn_walker(scene, 0, 0.0f, 0.3f, 1.75f, c0, 0.0f, 0.0f, 0.0f);
  Profiler profiler(120, false);
  std::vector<glm::vec3> prev, now;
  float prev_root = 0.0f, prev_step = 0.0f;
  Smoothness out;
  for (int f = 0; f < 720; ++f) {
    if (f == 150) scene.table(initial_slot(scene)).f32(kWalkerGait, kGaitCadenceTarget)[0] = c1;
    if (f == 400) scene.table(initial_slot(scene)).f32(kWalkerGait, kGaitCadenceTarget)[0] = c2;
    step(scene, 1.0f / 60.0f, profiler);
    WalkerLanes l = scene.lanes();
    gather_joint_positions(l, now);
    const float root = l.root_translation[l.stride];
    const float step = root - prev_root;
    if (f > 30) {  // past the start-up transient
      out.root_second_difference = std::max(out.root_second_difference, std::abs(step - prev_step));
      for (std::size_t j = 0; j < now.size(); ++j) out.joint_step = std::max(out.joint_step, glm::length(now[j] - prev[j]));
    }
    prev = now;
    prev_root = root;
    prev_step = step;
  }
  out.final_cadence = scene.table(initial_slot(scene)).f32(kWalkerGait, kGaitCadence)[0];
  return out;
}

// A cadence change must not pop: the pelvis may not accelerate harder than it does in steady walking at the
// cadences involved, and no joint may move faster than twice the swing foot's mean speed (2 stride / t_swing)
// at the fastest of them.
TEST(Locomotion, CadenceChangesWithoutPop) {
  const Smoothness changing = walk_with_cadences(90.0f, 130.0f, 80.0f);
  float steady = 0.0f;
  for (float c : {80.0f, 90.0f, 130.0f}) steady = std::max(steady, walk_with_cadences(c, c, c).root_second_difference);
  EXPECT_NEAR(changing.final_cadence, 80.0f, 0.01f) << "eased to the last target";
  EXPECT_LT(changing.root_second_difference, 1.25f * steady) << "the pelvis popped";
  const GaitParameters fast = gait_parameters(1.75f, 130.0f);
  const float swing_peak = 2.0f * fast.stride_length / fast.swing_time;
  EXPECT_LT(changing.joint_step, 1.1f * swing_peak / 60.0f) << "a joint jumped";
}

TEST(Locomotion, CrowdIsVariedAndLanesKeepTheirSpacing) {
  std::unique_ptr<Crowd> crowd = make_walkers(16, 5);
  Crowd& scene = *crowd;
  Profiler profiler(120, false);
  for (int f = 0; f < 30; ++f) step(scene, 1.0f / 30.0f, profiler);
  WalkerLanes l = scene.lanes();
  std::vector<float> heights, cadences;
  for (std::size_t w = 0; w < l.count; ++w) {
    heights.push_back(l.gait[kGaitHeight * l.stride + w]);
    cadences.push_back(l.gait[kGaitCadence * l.stride + w]);
  }
  auto spread = [](const std::vector<float>& v) {
    return *std::max_element(v.begin(), v.end()) - *std::min_element(v.begin(), v.end());
  };
  EXPECT_GT(spread(heights), 0.05f);
  EXPECT_GT(spread(cadences), 3.0f);
  // Same lane, same speed: a taller walker takes fewer, longer steps.
  for (std::size_t a = 0; a < l.count; ++a)
    for (std::size_t b = 0; b < l.count; ++b) {
      if (l.path[a] != l.path[b]) continue;
      const float ha = heights[a], hb = heights[b];
      if (ha > hb + 0.02f) {
        const float sa = gait_parameters(ha, cadences[a]).speed, sb = gait_parameters(hb, cadences[b]).speed;
        EXPECT_NEAR(sa, sb, 0.02f);
        EXPECT_LT(cadences[a], cadences[b]);
      }
    }
}

TEST(Locomotion, ArmsSwingInAntiPhaseWithTheLegs) {
  std::unique_ptr<Crowd> crowd = make_walkers(1);
  Crowd& scene = *crowd;
  Profiler profiler(120, false);
  const int lw = scene.rig().skeleton.find_joint("l_wrist"), la = scene.rig().skeleton.find_joint("l_ankle");
  double sum_ww = 0, sum_aa = 0, sum_wa = 0, mw = 0, ma = 0;
  std::vector<std::pair<float, float>> samples;
  for (int f = 0; f < 240; ++f) {
    step(scene, 1.0f / 60.0f, profiler);
    WalkerLanes l = scene.lanes();
    samples.push_back({l.world[(lw * kAffineFloats + 11) * l.stride], l.world[(la * kAffineFloats + 11) * l.stride]});
  }
  for (auto [w, a] : samples) mw += w, ma += a;
  mw /= samples.size();
  ma /= samples.size();
  for (auto [w, a] : samples) sum_ww += (w - mw) * (w - mw), sum_aa += (a - ma) * (a - ma), sum_wa += (w - mw) * (a - ma);
  const double correlation = sum_wa / std::sqrt(sum_ww * sum_aa);
  EXPECT_LT(correlation, -0.5) << "left wrist forward while the left foot is back";
}

TEST(Locomotion, SameResultForOneAndTwoThreads) {
  std::uint64_t hashes[2];
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    std::unique_ptr<Crowd> crowd = make_walkers(150, 3);
  Crowd& scene = *crowd;  // several 64-walker chunks
    Profiler profiler(120, false);
    for (int f = 0; f < 40; ++f) step(scene, 1.0f / 30.0f, profiler);
    hashes[threads - 1] = state_hash(scene);
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

TEST(Locomotion, RigWithoutLegsCannotWalkAndSaysWhy) {
  Rig rig;
  rig.skeleton.name = "torso";
  rig.skeleton.joint_names = {"HumanoidRoot", "vl5"};
  rig.skeleton.source_joint_names = rig.skeleton.joint_names;
  rig.skeleton.parents = {-1, 0};
  rig.skeleton.centers = {{0, 1, 0}, {0, 1.1f, 0}};
  rig.skeleton.limits.resize(2);
  rig.skeleton.stiffness.assign(2, glm::vec3(1.0f));
  Crowd scene(rig);
  EXPECT_NE(scene.motion.walk_error.find("l_hip"), std::string::npos) << scene.motion.walk_error;
  CrowdConfig config;
  config.motion = MotionSource::Walk;
  EXPECT_THROW(spawn_crowd(scene, config), std::invalid_argument);
}

// validate() rejects each missing or mismatched input, and run() then writes nothing: the per-frame job and the
// one that starts a walker.
TEST(LocomotionJob, JobValidity) {
  std::unique_ptr<Crowd> crowd = make_walkers(3);
  Crowd& scene = *crowd;
  SoaTable& table = scene.table(initial_slot(scene));
  const LocomotionRig& rig = *scene.motion.locomotion.get();
  const std::size_t written[] = {kWalkerGait, kWalkerClock, kWalkerPlacement, kWalkerRootTranslation,
                                 kWalkerLocalRotation, kWalkerIkGoal, kWalkerIkMode};
  // Gait state as spawned (the jobs validate it), every other written column the sentinel.
  for (std::size_t f : written)
    if (f != kWalkerGait) test::fill_sentinel(table, f);
  auto untouched = [&] {
    for (std::size_t f : written)
      if (f != kWalkerGait && !test::holds_sentinel(table, f)) return false;
    return true;
  };
  using namespace test;
  const LocomotionJob good = make_locomotion_job(rig, scene.motion.paths, table, 1.0f / 60.0f, scene.motion.style);
  LocomotionJob j = good;
  j.rig = nullptr;
  expect_refused(j, "no rig", untouched);
  j = good, j.style = nullptr;
  expect_refused(j, "no style", untouched);
  j = good, j.paths = {};
  expect_refused(j, "no paths", untouched);
  j = good, j.dt = std::numeric_limits<float>::quiet_NaN();
  expect_refused(j, "dt not finite", untouched);
  j = good, j.path = without_base(good.path);
  expect_refused(j, "no path indices", untouched);
  j = good, j.gait = with_components(good.gait, kGaitFloats - 1);
  expect_refused(j, "gait state of another layout", untouched);
  j = good, j.time = with_count(good.time, 2);
  expect_refused(j, "clock of fewer walkers", untouched);
  j = good, j.placement = with_stride(good.placement, 1);
  expect_refused(j, "placement stride below the walker count", untouched);
  j = good, j.local_rotation = with_components(good.local_rotation, 4 * 3);
  expect_refused(j, "rotations too few for the rig's joints", untouched);
  j = good, j.ik_goal = good.gait.columns(0, kIkLimbs * kIkGoalFloats);
  expect_refused(j, "goals written over the gait state", untouched);
  j = good, j.ik_mode = with_components(good.ik_mode, 2);
  expect_refused(j, "modes for two limbs only", untouched);
  LocomotionRig armless = rig;
  armless.limbs.resize(2);
  j = good, j.rig = &armless;
  expect_refused(j, "a rig without arm limbs", untouched);

  const float height = table.f32(kWalkerGait, kGaitHeight)[1];
  table.f32(kWalkerGait, kGaitHeight)[1] = 0.0f;
  expect_refused(good, "a walker of zero height", untouched);
  table.f32(kWalkerGait, kGaitHeight)[1] = height;
  table.f32(kWalkerGait, kGaitCadenceTarget)[1] = std::numeric_limits<float>::quiet_NaN();
  expect_refused(good, "a cadence target that is not a number", untouched);
  table.f32(kWalkerGait, kGaitCadenceTarget)[1] = 100.0f;

  StartWalkingJob start = make_start_walking_job(rig, scene.motion.paths, table, 2, scene.motion.style);
  StartWalkingJob s = start;
  s.walker = 3;
  expect_refused(s, "walker out of range", untouched);
  s = start, s.paths = {};
  expect_refused(s, "no paths", untouched);
  s = start, s.root_translation = without_base(start.root_translation);
  expect_refused(s, "no root translation output", untouched);

  EXPECT_TRUE(start.run());
  EXPECT_TRUE(good.run());
  EXPECT_FALSE(untouched());
}

}  // namespace
}  // namespace strata
