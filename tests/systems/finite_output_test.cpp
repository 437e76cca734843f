// No NaN ever leaves a system (docs/reliability.md): a property test driving IK and skinning (the vectorised
// kernel and its scalar twin) with 10,000 random extreme goals and poses each: unreachable and degenerate goals,
// collapsed limbs, huge and tiny scales, non-unit and zero quaternions. Every output must be finite.
// (The muscle system joins this test when it lands.)
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "components/skin_layout.h"
#include "io/hanim_loader.h"
#include "rig/body_rig.h"
#include "rig/muscle_binding.h"
#include "systems/fk.h"
#include "systems/muscle.h"
#include "scene/crowd.h"
#include "systems/ik.h"
#include "systems/skin_kernel.h"
#include "reference/skin_reference.h"
#include "rig/cor_centres.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"
#include "tests/sanitizer_scale.h"

namespace strata {
namespace {

// 10,000 in Release; a fifth under the sanitizers (tests/sanitizer_scale.h).
constexpr int kTrials = test::trials_for_build(10000, 5);

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(const glm::quat& q) {
  return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w);
}

// Extreme-value generator: magnitudes log-uniform over 1e-8..1e8 metres, exact zeros, and directions that line up
// with the pole or the limb.
struct Extremes {
  std::mt19937_64 rng{20240917};
  float uniform(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); }
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }
  float magnitude() { return std::pow(10.0f, uniform(-8.0f, 8.0f)); }
  glm::vec3 direction() {
    glm::vec3 d(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
    const float len = glm::length(d);
    return len > 1e-3f ? d / len : glm::vec3(0, 1, 0);
  }
  glm::vec3 vector() {
    switch (pick(6)) {
      case 0: return glm::vec3(0.0f);
      case 1: return glm::vec3(0.0f, -magnitude(), 0.0f);  // straight down a leg
      default: return magnitude() * direction();
    }
  }
  glm::quat quaternion() {
    switch (pick(5)) {
      case 0: return glm::quat(0, 0, 0, 0);                                    // zero
      case 1: return glm::quat(magnitude(), magnitude(), -magnitude(), 0.0f);  // far from unit
      default: return glm::normalize(glm::quat(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)));
    }
  }
};

// The shipped skeleton, optionally scaled and with one limb's segment collapsed to zero length.
Skeleton variant(const Skeleton& base, float scale, const LimbChain& limb, int collapse) {
  Skeleton s = base;
  for (glm::vec3& c : s.centers) c *= scale;
  if (collapse == 1) s.centers[limb.middle] = s.centers[limb.upper];  // upper segment of zero length
  if (collapse == 2) s.centers[limb.lower] = s.centers[limb.middle];  // lower segment of zero length
  if (collapse == 3) s.centers[limb.middle] = s.centers[limb.lower] = s.centers[limb.upper];  // the whole limb
  return s;
}

TEST(FiniteOutputs, IkOnTenThousandExtremeGoals) {
  const Skeleton base = load_default_humanoid().skeleton;
  const std::vector<LimbChain> limbs = make_limbs(base);
  ASSERT_EQ(limbs.size(), static_cast<std::size_t>(kLimbCount));
  Extremes x;
  int unreachable = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    const LimbChain& limb = limbs[static_cast<std::size_t>(x.pick(kLimbCount))];
    const float scale = x.pick(3) == 0 ? std::pow(10.0f, x.uniform(-4.0f, 4.0f)) : 1.0f;
    const Skeleton skeleton = variant(base, scale, limb, x.pick(5) == 0 ? 1 + x.pick(3) : 0);
    LimbChain chain = limb;
    chain.pole = x.pick(4) == 0 ? x.vector() : limb.pole;
    LimbSolveInput in;
    // Relative to the upper joint: from on top of it to far out of reach.
    in.goal = skeleton.centers[limb.upper] + x.vector();
    in.mode = x.pick(2) ? IkMode::Position : IkMode::PositionOrientation;
    in.orientation = x.quaternion();
    in.pole = x.pick(3) == 0 ? x.vector() : chain.pole;
    in.swivel_offset = x.pick(4) == 0 ? x.uniform(-1e6f, 1e6f) : x.uniform(-3.2f, 3.2f);
    const LimbSolveResult r = solve_limb(skeleton, chain, in);
    ASSERT_TRUE(finite(r.upper) && finite(r.middle) && finite(r.lower))
        << "trial " << trial << " goal " << in.goal.x << " " << in.goal.y << " " << in.goal.z << " scale " << scale;
    ASSERT_TRUE(std::isfinite(r.swivel) && std::isfinite(r.position_error)) << "trial " << trial;
    // Unit rotations: a finite but unnormalised quaternion would scale the limb downstream.
    ASSERT_NEAR(glm::length(r.upper), 1.0f, 1e-3f) << "trial " << trial;
    ASSERT_NEAR(glm::length(r.middle), 1.0f, 1e-3f) << "trial " << trial;
    unreachable += (r.flags & kIkUnreachable) ? 1 : 0;
  }
  // The generator does reach the degenerate regions it is meant to.
  EXPECT_GT(unreachable, kTrials / 10);
}

// IK, muscle and skinning together: the muscle system's forces, lengths and frames and the skin with its muscle
// displacement stay finite on every extreme pose (collapsed limbs, huge and tiny scales).
TEST(FiniteOutputs, SkinningOnTenThousandExtremePoses) {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  rig.muscles = default_muscle_rig();
  Crowd scene(rig);
  CrowdConfig config;
  config.walkers = 4;
  config.motion = MotionSource::Walk;
  spawn_crowd(scene, config);
  set_skinning_mode(scene, SkinningMode::CentresOfRotation);  // the layout then carries centres: every mode runs on it
  set_detail_level(scene, DetailLevel::mesh(2));  // the coarsest level: the property is per vertex, the count only costs time
  const BodyLevel& body = rig.body->levels[2];
  const std::vector<glm::vec3>& centres = body_cor_centres(*rig.body, 2)->centres;
  const SkinLayout& layout = current_layout(scene);
  const std::size_t padded = pad_to_lanes(layout.vertex_count);
  std::vector<float> out(6 * padded);
  const SkinOutput soa = skin_output_in(out.data(), padded);
  Profiler profiler(8, false);
  step(scene, 1.0f / 30.0f, profiler);
  WalkerLanes lanes = scene.lanes();
  Extremes x;
  const std::size_t s = lanes.stride;
  for (int trial = 0; trial < kTrials; ++trial) {
    const std::size_t w = static_cast<std::size_t>(trial) % lanes.count;
    // Every joint: a random, zero or far-from-unit quaternion; the root anywhere; the walker at any scale/heading.
    for (std::uint32_t j = 0; j < lanes.joints; ++j) {
      const glm::quat q = x.pick(3) == 0 ? x.quaternion() : glm::quat(1, 0, 0, 0);
      const float xyzw[4] = {q.x, q.y, q.z, q.w};
      for (int c = 0; c < 4; ++c) lanes.local_rotation[(j * 4 + c) * s + w] = xyzw[c];
    }
    const glm::vec3 root = x.pick(2) ? x.vector() : glm::vec3(0.0f);
    for (int c = 0; c < 3; ++c) lanes.root_translation[c * s + w] = root[c];
    const glm::vec3 where = x.pick(2) ? x.vector() : glm::vec3(0.0f);
    for (int c = 0; c < 3; ++c) lanes.placement[c * s + w] = where[c];
    lanes.placement[3 * s + w] = x.pick(4) == 0 ? x.uniform(-1e6f, 1e6f) : x.uniform(-3.2f, 3.2f);
    lanes.placement[4 * s + w] = std::pow(10.0f, x.uniform(-6.0f, 6.0f));
    ASSERT_TRUE(make_fk_job(rig.skeleton, scene.table(initial_slot(scene))).run());
    ASSERT_TRUE(make_muscle_job(rig.muscles->set, scene.table(initial_slot(scene))).run());
    for (std::size_t p = 0; p < lanes.muscle_points; ++p) {
      ASSERT_TRUE(std::isfinite(lanes.at(lanes.muscle_force, p)[w]) && std::isfinite(lanes.at(lanes.muscle_length, p)[w]))
          << "muscle, trial " << trial << ", control point " << p;
      for (int c = 0; c < 6; ++c) ASSERT_TRUE(std::isfinite(lanes.at(lanes.muscle_frame, p * 6 + c)[w]));
    }

    // Every skinning mode: zero and far-from-unit joint quaternions reach the dual-quaternion and centre-of-rotation
    // paths as degenerate skinning matrices.
    for (const SkinningMode mode : kSkinningModes) {
      ASSERT_TRUE(make_skin_walker_job(layout, scene.table(initial_slot(scene)), w, soa, mode).run());
      for (std::size_t i = 0; i < layout.vertex_count; ++i)
        ASSERT_TRUE(std::isfinite(soa.px[i]) && std::isfinite(soa.py[i]) && std::isfinite(soa.pz[i]) &&
                    std::isfinite(soa.nx[i]) && std::isfinite(soa.ny[i]) && std::isfinite(soa.nz[i]))
            << "kernel " << skinning_mode_name(mode) << ", trial " << trial << ", vertex " << i << ", scale "
            << lanes.placement[4 * s + w];
      // The scalar twin on every tenth pose (it is ~20x slower and the same property).
      if (trial % 10 == 0) {
        const std::vector<float> force = walker_muscle_forces(lanes, w);
        const MuscleReference muscles{&rig.muscles->set, &rig.muscles->levels[2], scene.skin.gains, force};
        const SkinnedVertices ref =
            skin_reference(body.mesh, body.binding, walker_skinning_matrices(lanes, w), mode, centres, muscles);
        for (std::size_t v = 0; v < ref.positions.size(); ++v)
          ASSERT_TRUE(finite(ref.positions[v]) && finite(ref.normals[v]))
              << "reference " << skinning_mode_name(mode) << ", trial " << trial << ", vertex " << v;
      }
    }
  }
}

}  // namespace
}  // namespace strata
