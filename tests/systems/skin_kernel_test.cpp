// The vectorised skinning kernel against its scalar twin (the paper's equation 4 in double precision), on every
// level of the shipped body and on random poses; the layout's bookkeeping; thread-count determinism.
#include <gtest/gtest.h>

#include <random>
#include <set>

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
#include "reference/skin_reference.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"
#include "tests/systems/job_test_util.h"

namespace strata {
namespace {

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

// Kernel vs reference (equation 4 plus the muscle displacement, evaluated from the binding in double) over
// walking frames and random joint rotations, every level.
// Both compiled bodies (AVX2 + FMA where the CPU has it, and the portable SSE2 one) are held to the twin.
class SkinKernelIsaTest : public ::testing::TestWithParam<SkinKernelIsa> {
 protected:
  void SetUp() override {
    if (GetParam() == SkinKernelIsa::Avx2Fma && !__builtin_cpu_supports("avx2")) GTEST_SKIP() << "no AVX2 here";
    force_skin_kernel_isa(GetParam());
  }
  void TearDown() override { force_skin_kernel_isa(SkinKernelIsa::Auto); }
};

TEST_P(SkinKernelIsaTest, MatchesTheScalarReferenceOnEveryLevelAndRandomPoses) {
  ASSERT_EQ(skin_kernel_isa(), GetParam());
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
    set_detail_level(scene, DetailLevel::mesh(level));
    const SkinLayout& layout = current_layout(scene);
    const BodyLevel& body = rig.body->levels[static_cast<std::size_t>(level)];
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
        ASSERT_TRUE(make_skin_walker_job(layout, scene.table(initial_slot(scene)), w, soa).run());
        const std::vector<float> force = walker_muscle_forces(lanes, w);
        const MuscleReference muscles{&rig.muscles->set, &rig.muscles->levels[static_cast<std::size_t>(level)],
                                      scene.skin.gains, force};
        const SkinnedVertices ref =
            skin_reference(body.mesh, body.binding, walker_skinning_matrices(lanes, w), muscles);
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

INSTANTIATE_TEST_SUITE_P(BothBodies, SkinKernelIsaTest,
                         ::testing::Values(SkinKernelIsa::Avx2Fma, SkinKernelIsa::Portable),
                         [](const auto& info) { return std::string(info.param == SkinKernelIsa::Avx2Fma ? "Avx2Fma" : "Portable"); });

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

// validate() rejects each missing or mismatched input, and run() then writes nothing: the per-walker kernel job,
// the crowd job and the cage's muscle displacement.
TEST(SkinJobs, JobValidity) {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  rig.muscles = default_muscle_rig();
  Crowd scene(rig);
  CrowdConfig config;
  config.walkers = 3;
  config.motion = MotionSource::Walk;
  spawn_crowd(scene, config);
  set_detail_level(scene, DetailLevel::mesh(2));
  Profiler profiler(8, false);
  step(scene, 0.1f, profiler);
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
