// The vectorised skinning kernel against its scalar twin (the paper's equation 4 in double precision), on every
// level of the shipped body and on random poses; the layout's bookkeeping; thread-count determinism.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <set>
#include <tuple>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <tbb/global_control.h>

#include "components/skin_layout.h"
#include "io/hanim_loader.h"
#include "rig/body_rig.h"
#include "rig/muscle_binding.h"
#include "systems/fk.h"
#include "scene/crowd.h"
#include "systems/muscle.h"
#include "systems/skin.h"
#include "systems/skin_kernel.h"
#include "reference/fk_reference.h"
#include "reference/skin_reference.h"
#include "rig/cor_centres.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"
#include "tests/systems/job_test_util.h"

namespace strata {
namespace {

// The shipped rig with its muscle layer.
Rig muscled_rig() {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  rig.muscles = default_muscle_rig();
  return rig;
}

// `walkers` walkers of `rig` walking at mesh level `level`, stepped `frames` times by 0.1 s.
std::unique_ptr<Crowd> walking_crowd(const Rig& rig, std::size_t walkers, int level, int frames) {
  auto scene = std::make_unique<Crowd>(rig);
  CrowdConfig config;
  config.walkers = walkers;
  config.motion = MotionSource::Walk;
  spawn_crowd(*scene, config);
  set_detail_level(*scene, DetailLevel::mesh(level));
  Profiler profiler(8, false);
  for (int f = 0; f < frames; ++f) step(*scene, 0.1f, profiler);
  return scene;
}

TEST(SkinLayout, GroupsCoverEveryVertexOnceAndTrianglesFollowTheRenumbering) {
  const auto body = default_bound_body();
  for (const BodyLevel& level : body->levels) {
    const SkinLayout layout = make_skin_layout(level);
    ASSERT_EQ(layout.vertex_count, level.mesh.vertex_count());
    std::uint32_t next = 0;
    for (const SkinGroup& g : layout.groups) {
      EXPECT_EQ(g.first, next) << "groups are contiguous";
      EXPECT_GE(g.influences, 1u);
      EXPECT_LE(g.influences, static_cast<std::uint32_t>(kMaxInfluences));
      for (std::uint32_t i = g.first; i < g.first + g.count; ++i) {
        float sum = 0.0f;
        for (std::uint32_t k = 0; k < g.influences; ++k) sum += layout.weight[k][i];
        ASSERT_NEAR(sum, 1.0f, 1e-5f);
      }
      next += g.count;
    }
    EXPECT_EQ(next, layout.vertex_count);
    EXPECT_EQ(std::set<std::uint32_t>(layout.original.begin(), layout.original.end()).size(), layout.vertex_count);
    ASSERT_EQ(layout.triangles.size(), level.mesh.triangles.size());
    for (std::size_t t = 0; t < layout.triangles.size(); ++t)
      ASSERT_EQ(layout.original[layout.triangles[t]], level.mesh.triangles[t]);
  }
}

// Kernel vs reference (equation 4, dual quaternions or centres of rotation, plus the muscle displacement
// evaluated from the binding in double) over walking frames and random joint rotations, every level.
// Every compiled body the CPU runs (AVX-512 and AVX2 + FMA where it has them, and the portable SSE2 one) is held
// to the twin in every mode; a body the CPU cannot run is skipped, and the skip names it.
using IsaMode = std::tuple<SkinKernelIsa, SkinningMode>;
class SkinKernelIsaTest : public ::testing::TestWithParam<IsaMode> {
 protected:
  void SetUp() override {
    const SkinKernelIsa isa = std::get<0>(GetParam());
    if (!skin_kernel_isa_supported(isa))
      GTEST_SKIP() << "the " << skin_kernel_isa_name(isa) << " body is compiled but this CPU cannot run it";
    force_skin_kernel_isa(isa);
  }
  void TearDown() override { force_skin_kernel_isa(SkinKernelIsa::Auto); }
};

TEST_P(SkinKernelIsaTest, MatchesTheScalarReferenceOnEveryLevelAndRandomPoses) {
  const auto [isa, mode] = GetParam();
  ASSERT_EQ(skin_kernel_isa(), isa);
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  rig.muscles = default_muscle_rig();
  std::mt19937_64 rng(11);
  std::normal_distribution<float> gauss(0.0f, 0.35f);
  for (int level = 0; level < 3; ++level) {
    Crowd scene(rig);
    CrowdConfig config;
    config.walkers = 3;
    config.motion = MotionSource::Walk;
    spawn_crowd(scene, config);
    set_skinning_mode(scene, mode);
    set_detail_level(scene, DetailLevel::mesh(level));
    const SkinLayout& layout = current_layout(scene);
    const BodyLevel& body = rig.body->levels[static_cast<std::size_t>(level)];
    std::vector<glm::vec3> centres;
    if (mode == SkinningMode::CentresOfRotation) {
      ASSERT_TRUE(layout.has_cor_centres());
      centres = body_cor_centres(*rig.body, level)->centres;
    }
    Profiler profiler(8, false);
    const std::size_t padded = pad_to_lanes(layout.vertex_count);
    std::vector<float> out(6 * padded);
    const SkinOutput soa = skin_output_in(out.data(), padded);
    float worst_p = 0.0f, worst_n = 0.0f;
    for (int trial = 0; trial < 6; ++trial) {
      step(scene, 0.13f, profiler);
      WalkerLanes lanes = scene.lanes();
      if (trial >= 3) {  // walker 1: a random rotation on every joint, then FK again
        for (std::uint32_t j = 0; j < lanes.joints; ++j) {
          const glm::quat q = glm::normalize(glm::quat(1.0f, gauss(rng), gauss(rng), gauss(rng)));
          const float xyzw[4] = {q.x, q.y, q.z, q.w};
          for (int c = 0; c < 4; ++c) lanes.local_rotation[(j * 4 + c) * lanes.stride + 1] = xyzw[c];
        }
        ASSERT_TRUE(make_fk_job(rig.skeleton, scene.table(initial_slot(scene))).run());
        ASSERT_TRUE(make_muscle_job(rig.muscles->set, scene.table(initial_slot(scene))).run());
      }
      for (std::size_t w = 0; w < lanes.count; ++w) {
        ASSERT_TRUE(make_skin_walker_job(layout, scene.table(initial_slot(scene)), w, soa, mode).run());
        const std::vector<float> force = walker_muscle_forces(lanes, w);
        const MuscleReference muscles{&rig.muscles->set, &rig.muscles->levels[static_cast<std::size_t>(level)],
                                      scene.skin.gains, force};
        const SkinnedVertices ref =
            skin_reference(body.mesh, body.binding, walker_skinning_matrices(lanes, w), mode, centres, muscles);
        const Placement P = placement_of(lanes, w);
        for (std::size_t i = 0; i < layout.vertex_count; ++i) {
          const std::uint32_t v = layout.original[i];
          const glm::vec3 pos{soa.px[i], soa.py[i], soa.pz[i]}, nrm{soa.nx[i], soa.ny[i], soa.nz[i]};
          worst_p = std::max(worst_p, glm::length(P.point(ref.positions[v]) - pos));
          worst_n = std::max(worst_n, glm::length(P.direction(ref.normals[v]) - nrm));
          ASSERT_TRUE(std::isfinite(pos.x + pos.y + pos.z + nrm.x + nrm.y + nrm.z));
        }
      }
    }
    EXPECT_LT(worst_p, 1e-5f) << "level " << level;
    EXPECT_LT(worst_n, 1e-4f) << "level " << level;
  }
}

INSTANTIATE_TEST_SUITE_P(
    EveryBodyEveryMode, SkinKernelIsaTest,
    ::testing::Combine(::testing::Values(SkinKernelIsa::Avx512, SkinKernelIsa::Avx2Fma, SkinKernelIsa::Portable),
                       ::testing::ValuesIn(kSkinningModes)),
    [](const auto& info) {
      const SkinKernelIsa isa = std::get<0>(info.param);
      const char* name = isa == SkinKernelIsa::Avx512 ? "Avx512" : isa == SkinKernelIsa::Avx2Fma ? "Avx2Fma" : "Portable";
      return std::string(name) + "_" + skinning_mode_name(std::get<1>(info.param));
    });

// The non-linear modes at rest are the rest mesh (placed), like linear blending: no drift from the quaternion
// round trip beyond float noise, and centres of rotation cancel out at rest (R = I, LBS(c) = c).
TEST(SkinModes, RestPoseIsTheRestMeshInEveryMode) {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  const BodyLevel& body = rig.body->levels[1];
  std::vector<glm::mat4> identity(rig.skeleton.joint_count(), glm::mat4(1.0f));
  const std::vector<glm::vec3>& centres = body_cor_centres(*rig.body, 1)->centres;
  for (const SkinningMode mode : kSkinningModes) {
    const SkinnedVertices ref = skin_reference(body.mesh, body.binding, identity, mode, centres);
    float worst = 0.0f;
    for (std::size_t v = 0; v < body.mesh.vertex_count(); ++v)
      worst = std::max(worst, glm::length(ref.positions[v] - body.mesh.positions[v]));
    EXPECT_LT(worst, 1e-6f) << skinning_mode_name(mode);
  }
}

// The forearm turned by 180 deg about its own axis at the elbow (the shipped binding blends forearm and upper arm
// there; the wrist is a hard seam between parts): linear blending pinches the blended vertices towards the axis
// (the candy wrapper), dual quaternions and centres of rotation keep them at their distance from it.
TEST(SkinModes, TwistKeepsTheForearmRadiusWithoutLinearBlending) {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  const Skeleton& s = rig.skeleton;
  const BodyLevel& body = rig.body->levels[1];
  const int elbow = s.find_joint("l_elbow"), wrist = s.find_joint("l_wrist");
  ASSERT_GE(elbow, 0);
  ASSERT_GE(wrist, 0);
  const glm::vec3 a = s.centers[static_cast<std::size_t>(elbow)], b = s.centers[static_cast<std::size_t>(wrist)];
  const glm::vec3 axis = glm::normalize(b - a);
  std::vector<glm::quat> rotations(s.joint_count(), glm::quat(1, 0, 0, 0));
  rotations[static_cast<std::size_t>(elbow)] = glm::angleAxis(3.14159265f, axis);
  const ReferencePose pose = fk_reference(s, rotations, glm::vec3(0.0f));
  const std::vector<glm::vec3>& centres = body_cor_centres(*rig.body, 1)->centres;
  auto radius = [&](const glm::vec3& p) { return glm::length((p - a) - glm::dot(p - a, axis) * axis); };
  for (const SkinningMode mode : kSkinningModes) {
    const SkinnedVertices ref = skin_reference(body.mesh, body.binding, pose.skinning, mode, centres);
    double kept = 0.0;
    int blended = 0;
    for (std::size_t v = 0; v < body.mesh.vertex_count(); ++v) {
      float we = 0.0f;
      for (int k = 0; k < kMaxInfluences; ++k)
        we += body.binding.joints[v][k] == elbow ? body.binding.weights[v][k] : 0.0f;
      if (we < 0.3f || we > 0.7f) continue;  // only the vertices truly blended between upper arm and forearm
      kept += radius(ref.positions[v]) / std::max(radius(body.mesh.positions[v]), 1e-6f);
      ++blended;
    }
    ASSERT_GT(blended, 0);
    kept /= blended;
    if (mode == SkinningMode::Linear)
      EXPECT_LT(kept, 0.6) << "linear blending collapses a half-turn twist";
    else
      EXPECT_GT(kept, 0.9) << skinning_mode_name(mode);
  }
}

TEST(SkinKernel, SameBytesForOneAndTwoThreads) {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  rig.muscles = default_muscle_rig();
  std::vector<float> result[2];
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    Crowd scene(rig);
    CrowdConfig config;
    config.walkers = 24;  // several 4-walker chunks
    config.motion = MotionSource::Walk;
    spawn_crowd(scene, config);
    set_detail_level(scene, DetailLevel::mesh(2));
    Profiler profiler(8, false);
    for (int f = 0; f < 5; ++f) step(scene, 1.0f / 30.0f, profiler);
    const SkinnedCrowd& s = current_skinned(scene);
    for (const AlignedBuffer<float>* b : {&s.px, &s.py, &s.pz, &s.nx, &s.ny, &s.nz})
      result[threads - 1].insert(result[threads - 1].end(), b->data(), b->data() + s.walkers * s.stride);
  }
  ASSERT_EQ(result[0].size(), result[1].size());
  EXPECT_TRUE(result[0] == result[1]);
}

// Groups of every size, in every mode and on every compiled body the CPU runs: the layout's groups cut into runs
// of 1, 2, 7, 15, 16, 17, 31, 32, 33 and 50 vertices (the same vertices, joints and weights) skin to the same
// results as the uncut layout (to float rounding: a vertex may fall in a loop's scalar remainder in one and in a
// vector lane in the other), the last run (at most 3 vertices) ending at the layout's end. Then only every other
// run is kept: the kernel writes exactly those runs' rows, and no row of a group it was not given nor of the
// padding.
TEST(SkinKernel, GroupsOfEverySizeGiveTheSameResultsAndWriteOnlyTheirOwnRows) {
  const Rig rig = muscled_rig();
  const std::unique_ptr<Crowd> walking = walking_crowd(rig, 2, 1, 4);
  Crowd& scene = *walking;
  for (const SkinningMode mode : kSkinningModes) {
    set_skinning_mode(scene, mode);
    const SkinLayout& whole = current_layout(scene);
    SkinLayout cut = whole;
    cut.groups.clear();
    const std::uint32_t sizes[] = {1, 2, 7, 15, 16, 17, 31, 32, 33, 50};
    std::size_t next_size = 0;
    for (const SkinGroup& g : whole.groups)
      for (std::uint32_t at = g.first, end = g.first + g.count; at < end;) {
        SkinGroup run = g;
        run.first = at;
        const std::uint32_t left = end - at;
        run.count = std::min(left, sizes[next_size++ % std::size(sizes)]);
        if (end == whole.vertex_count && left - run.count < 3) run.count = left <= 3 ? left : left - 3;  // end on 3
        cut.groups.push_back(run);
        at += run.count;
      }
    const std::size_t padded = pad_to_lanes(whole.vertex_count);
    ASSERT_LE(cut.groups.back().count, 3u);
    ASSERT_EQ(cut.groups.back().first + cut.groups.back().count, whole.vertex_count);
    ASSERT_GT(cut.groups.back().first + kSimdLaneFloats, padded) << "the last run should end inside the last block";
    SkinLayout alternate = cut;
    alternate.groups.clear();
    for (std::size_t i = 0; i < cut.groups.size(); i += 2) alternate.groups.push_back(cut.groups[i]);
    for (const SkinKernelIsa isa : {SkinKernelIsa::Avx512, SkinKernelIsa::Avx2Fma, SkinKernelIsa::Portable}) {
      if (!skin_kernel_isa_supported(isa)) continue;
      force_skin_kernel_isa(isa);
      struct BackToAuto {  // also when an assertion below returns early
        ~BackToAuto() { force_skin_kernel_isa(SkinKernelIsa::Auto); }
      } back_to_auto;
      const char* what = skin_kernel_isa_name(isa);
      auto skin = [&](const SkinLayout& layout, std::size_t walker) {
        std::vector<float> out(6 * padded, test::kSentinel);  // no skinned coordinate or normal takes it
        EXPECT_TRUE(make_skin_walker_job(layout, scene.table(initial_slot(scene)), walker,
                                         skin_output_in(out.data(), padded), mode).run());
        return out;
      };
      for (std::size_t walker = 0; walker < 2; ++walker) {
        const std::vector<float> expected = skin(whole, walker);
        const std::vector<float> cut_out = skin(cut, walker);
        float worst = 0.0f;
        for (std::size_t c = 0; c < 6; ++c)
          for (std::size_t i = 0; i < whole.vertex_count; ++i)
            worst = std::max(worst, std::abs(cut_out[c * padded + i] - expected[c * padded + i]));
        EXPECT_LT(worst, 2e-6f) << skinning_mode_name(mode) << " " << what;
        std::vector<char> kept(padded, 0);
        for (const SkinGroup& g : alternate.groups) std::fill_n(kept.begin() + g.first, g.count, 1);
        const std::vector<float> some = skin(alternate, walker);
        for (std::size_t c = 0; c < 6; ++c)
          for (std::size_t i = 0; i < padded; ++i)
            if (kept[i])
              ASSERT_NEAR(some[c * padded + i], expected[c * padded + i], 2e-6f)
                  << skinning_mode_name(mode) << " " << what << " column " << c << " row " << i;
            else
              ASSERT_EQ(some[c * padded + i], test::kSentinel)
                  << skinning_mode_name(mode) << " " << what << " column " << c << " row " << i << " written";
      }
    }
  }
}

// validate() rejects each missing or mismatched input, and run() then writes nothing: the per-walker kernel job,
// the crowd job and the cage's muscle displacement.
TEST(SkinJobs, JobValidity) {
  const Rig rig = muscled_rig();
  const std::unique_ptr<Crowd> walking = walking_crowd(rig, 3, 2, 1);
  Crowd& scene = *walking;
  const SkinLayout& layout = current_layout(scene);
  ASSERT_TRUE(layout.muscle_points > 0);
  const SoaTable& table = scene.table(initial_slot(scene));
  using namespace test;

  // SkinWalkerJob: one walker into a plain block.
  const std::size_t padded = pad_to_lanes(layout.vertex_count);
  std::vector<float> block(6 * padded, kSentinel);
  auto block_untouched = [&] {
    for (float v : block)
      if (v != kSentinel) return false;
    return true;
  };
  const SkinWalkerJob good = make_skin_walker_job(layout, table, 2, skin_output_in(block.data(), padded));
  SkinWalkerJob j = good;
  j.layout = nullptr;
  expect_refused(j, "no layout", block_untouched);
  j = good, j.walker = 3;
  expect_refused(j, "walker out of range", block_untouched);
  j = good, j.skinning = without_base(good.skinning);
  expect_refused(j, "no skinning matrices", block_untouched);
  j = good, j.skinning = with_components(good.skinning, 12 * 3);
  expect_refused(j, "too few joints for the layout's groups", block_untouched);
  j = good, j.placement = with_components(good.placement, 4);
  expect_refused(j, "placement without scale", block_untouched);
  j = good, j.placement = with_count(good.placement, 2);
  expect_refused(j, "placement of fewer walkers", block_untouched);
  j = good, j.muscle_force = with_components(good.muscle_force, layout.muscle_points - 1);
  expect_refused(j, "fewer force columns than the layout's muscle points", block_untouched);
  j = good, j.out.capacity = layout.vertex_count - 1;
  expect_refused(j, "output too short", block_untouched);
  j = good, j.out.nz = nullptr;
  expect_refused(j, "an output array missing", block_untouched);
  SkinLayout bad_group = layout;
  bad_group.groups[0].joints[0] = 999;
  j = good, j.layout = &bad_group;
  expect_refused(j, "a group on a joint the rig lacks", block_untouched);
  EXPECT_TRUE(good.run());
  EXPECT_FALSE(block_untouched());

  // SkinJob: a prepared crowd; a wrongly prepared one is refused.
  SkinnedCrowd crowd;
  const std::vector<std::uint32_t> subset = {2, 0};
  const SkinJob crowd_job = make_skin_job(layout, table, crowd, &subset);
  auto crowd_untouched = [&] {
    for (const AlignedBuffer<float>* b : {&crowd.px, &crowd.py, &crowd.pz, &crowd.nx, &crowd.ny, &crowd.nz})
      for (std::size_t i = 0; i < b->size(); ++i)
        if ((*b)[i] != kSentinel) return false;
    return true;
  };
  for (AlignedBuffer<float>* b : {&crowd.px, &crowd.py, &crowd.pz, &crowd.nx, &crowd.ny, &crowd.nz})
    for (std::size_t i = 0; i < b->size(); ++i) (*b)[i] = kSentinel;
  SkinJob c = crowd_job;
  c.out = nullptr;
  expect_refused(c, "no output crowd", crowd_untouched);
  const std::vector<std::uint32_t> past_end = {2, 3};
  c = crowd_job, c.walkers = &past_end;
  expect_refused(c, "a walker row past the table", crowd_untouched);
  c = crowd_job, c.walkers = nullptr;
  expect_refused(c, "crowd prepared for a subset, job over everyone", crowd_untouched);
  c = crowd_job;
  SkinLayout other = make_skin_layout(rig.body->levels[1]);
  c.layout = &other;
  expect_refused(c, "crowd prepared for another level", crowd_untouched);
  c = crowd_job, c.muscle_force = without_base(crowd_job.muscle_force);
  expect_refused(c, "no force columns", crowd_untouched);
  EXPECT_TRUE(crowd_job.run());
  EXPECT_FALSE(crowd_untouched());

  // MuscleDisplacementJob.
  MuscleDisplacementList list;
  list.vertex = {0, 5};
  list.point = {{0, 1, 2}, {3, 4, 5}};
  list.coefficient = {{0.1f, 0.2f, 0.3f}, {0.3f, 0.2f, 0.1f}};
  std::fill(block.begin(), block.end(), kSentinel);
  const SkinColumns columns = skin_columns(table);
  const MuscleDisplacementJob move{&list, columns.placement, columns.muscle_force, 1,
                                   skin_output_in(block.data(), padded)};
  MuscleDisplacementJob m = move;
  m.list = nullptr;
  expect_refused(m, "no list", block_untouched);
  MuscleDisplacementList ragged = list;
  ragged.coefficient.pop_back();
  m = move, m.list = &ragged;
  expect_refused(m, "arrays of different lengths", block_untouched);
  MuscleDisplacementList far_point = list;
  far_point.point[1][2] = columns.muscle_force.components;
  m = move, m.list = &far_point;
  expect_refused(m, "a control point past the force columns", block_untouched);
  m = move, m.out.capacity = 5;
  expect_refused(m, "a vertex past the output", block_untouched);
  m = move, m.walker = 3;
  expect_refused(m, "walker out of range", block_untouched);
  EXPECT_TRUE(move.run());
  EXPECT_FALSE(block_untouched());
}

}  // namespace
}  // namespace strata
