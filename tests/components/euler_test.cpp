// The joint-limit Euler convention R = Rx(x) Rz(z) Ry(y), |z| <= pi/2 (components/euler.h).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "components/euler.h"

namespace strata {
namespace {

constexpr float kPi = 3.14159265358979f;

// Difference of two angles, wrapped into [-pi, pi].
float angle_diff(float a, float b) { return std::remainder(a - b, 2.0f * kPi); }

float max_abs_diff(const glm::mat3& a, const glm::mat3& b) {
  float d = 0.0f;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) d = std::max(d, std::abs(a[c][r] - b[c][r]));
  return d;
}

// The convention built independently, from glm's axis-angle quaternions.
glm::mat3 composed(const glm::vec3& a) {
  const glm::quat q = glm::angleAxis(a.x, glm::vec3(1, 0, 0)) * glm::angleAxis(a.z, glm::vec3(0, 0, 1)) *
                      glm::angleAxis(a.y, glm::vec3(0, 1, 0));
  return glm::mat3_cast(q);
}

TEST(Euler, RotationFromAnglesIsRxRzRy) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> any(-kPi, kPi);
  for (int i = 0; i < 1000; ++i) {
    const glm::vec3 a(any(rng), any(rng), any(rng));
    EXPECT_LT(max_abs_diff(rotation_from_limit_angles(a), composed(a)), 2e-6f);
  }
}

TEST(Euler, RoundTripAwayFromTheLock) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> any(-kPi, kPi);
  std::uniform_real_distribution<float> tilt(-1.5f, 1.5f);  // |z| < pi/2 with 4 degrees to spare
  float worst = 0.0f;
  for (int i = 0; i < 20000; ++i) {
    const glm::vec3 a(any(rng), any(rng), tilt(rng));
    const glm::vec3 back = limit_angles(rotation_from_limit_angles(a));
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(angle_diff(back[k], a[k])));
  }
  EXPECT_LT(worst, 1e-5f);
}

TEST(Euler, SingleAxisRotationsReadBackOnTheirAxis) {
  const glm::vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int k = 0; k < 3; ++k) {
    for (float angle : {-1.2f, -0.3f, 0.4f, 1.1f}) {
      const glm::vec3 got = limit_angles(glm::mat3_cast(glm::angleAxis(angle, axes[k])));
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], c == k ? angle : 0.0f, 1e-6f) << "axis " << k;
    }
  }
  EXPECT_EQ(limit_angles(glm::mat3(1.0f)), glm::vec3(0.0f));
}

TEST(Euler, TiltBeyondHalfPiTakesTheOtherBranch) {
  // (x, y, z) and (x + pi, y + pi, pi - z) are the same rotation; only the second has |z| <= pi/2 when z = 2.
  const glm::vec3 a(0.3f, -0.4f, 2.0f);
  const glm::vec3 got = limit_angles(rotation_from_limit_angles(a));
  EXPECT_LE(std::abs(got.z), kPi / 2 + 1e-6f);
  EXPECT_NEAR(angle_diff(got.x, a.x + kPi), 0.0f, 1e-5f);
  EXPECT_NEAR(angle_diff(got.y, a.y + kPi), 0.0f, 1e-5f);
  EXPECT_NEAR(got.z, kPi - a.z, 1e-5f);
  EXPECT_LT(max_abs_diff(rotation_from_limit_angles(got), composed(a)), 2e-6f);
}

TEST(Euler, GimbalLockPutsEverythingInXAndStaysFinite) {
  for (float z : {kPi / 2, -kPi / 2}) {
    for (float x : {-2.0f, 0.0f, 0.7f}) {
      for (float y : {-0.5f, 0.0f, 1.3f}) {
        const glm::mat3 r = composed({x, y, z});
        const glm::vec3 got = limit_angles(r);
        ASSERT_TRUE(std::isfinite(got.x) && std::isfinite(got.y) && std::isfinite(got.z));
        EXPECT_EQ(got.y, 0.0f) << "at the lock y is set to 0";
        EXPECT_NEAR(std::abs(got.z), kPi / 2, 1e-3f);
        // Only x - y (z = +pi/2) or x + y (z = -pi/2) is defined; x carries it.
        EXPECT_NEAR(angle_diff(got.x, z > 0 ? x - y : x + y), 0.0f, 1e-3f);
        EXPECT_LT(max_abs_diff(rotation_from_limit_angles(got), r), 1e-3f);
      }
    }
  }
  // Just off the lock the decomposition must still reproduce the rotation.
  const glm::mat3 near_lock = composed({0.4f, -0.9f, kPi / 2 - 1e-4f});
  EXPECT_LT(max_abs_diff(rotation_from_limit_angles(limit_angles(near_lock)), near_lock), 1e-4f);
}

TEST(Euler, ViolationSumsTheDistanceOutsideEachAxis) {
  JointLimits limits;
  limits.lower = {-1.0f, -0.5f, -0.2f};
  limits.upper = {1.0f, 0.5f, 0.2f};
  limits.present = true;
  EXPECT_EQ(limit_violation(limits, {0.0f, 0.0f, 0.0f}), 0.0f);
  EXPECT_EQ(limit_violation(limits, {1.0f, -0.5f, 0.2f}), 0.0f) << "the bounds themselves are inside";
  EXPECT_NEAR(limit_violation(limits, {1.5f, 0.0f, -0.5f}), 0.5f + 0.3f, 1e-6f);
  EXPECT_NEAR(limit_violation(limits, {-1.25f, 0.75f, 0.0f}), 0.25f + 0.25f, 1e-6f);

  JointLimits none = limits;
  none.present = false;
  EXPECT_EQ(limit_violation(none, {3.0f, 3.0f, 3.0f}), 0.0f) << "no limits: nothing is violated";
}

TEST(Euler, ClampMovesOnlyTheViolatingAxes) {
  JointLimits limits;
  limits.lower = {-1.0f, -0.5f, -0.2f};
  limits.upper = {1.0f, 0.5f, 0.2f};
  limits.present = true;
  EXPECT_EQ(clamp_to_limits(limits, {1.5f, 0.1f, -0.5f}), glm::vec3(1.0f, 0.1f, -0.2f));
  EXPECT_EQ(clamp_to_limits(limits, {0.3f, -0.4f, 0.1f}), glm::vec3(0.3f, -0.4f, 0.1f));
  const glm::vec3 out = clamp_to_limits(limits, {-7.0f, 9.0f, 0.0f});
  EXPECT_EQ(limit_violation(limits, out), 0.0f);

  JointLimits none = limits;
  none.present = false;
  EXPECT_EQ(clamp_to_limits(none, {3.0f, -3.0f, 1.0f}), glm::vec3(3.0f, -3.0f, 1.0f));
}

}  // namespace
}  // namespace strata
