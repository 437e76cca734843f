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
        fk_system(rig.skeleton, lanes);
        muscle_system(rig.muscles->set, lanes);
      }
      for (std::size_t w = 0; w < lanes.count; ++w) {
        skin_walker(layout, lanes, w, soa);
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

}  // namespace
}  // namespace strata
