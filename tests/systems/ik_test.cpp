// Analytic limb IK (systems/ik.h) on the shipped skeleton, checked against the independent FK reference.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>

#include <glm/gtc/quaternion.hpp>
#include <tbb/global_control.h>

#include "components/euler.h"
#include "components/walker.h"
#include "io/hanim_loader.h"
#include "systems/fk.h"
#include "reference/fk_reference.h"
#include "tests/systems/job_test_util.h"
#include "systems/ik.h"

namespace strata {
namespace {

constexpr float kLimitTolerance = 1e-4f;  // rad: float round trip of the solver's (double) limit test

const Skeleton& shipped() {
  static const Skeleton skeleton = load_default_humanoid().skeleton;
  return skeleton;
}

bool finite(const glm::quat& q) {
  return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w);
}
bool finite(const LimbSolveResult& r) {
  return finite(r.upper) && finite(r.middle) && finite(r.lower) && std::isfinite(r.swivel) &&
         std::isfinite(r.position_error);
}

glm::vec3 uniform_in_limits(std::mt19937_64& rng, const JointLimits& l) {
  glm::vec3 a;
  for (int k = 0; k < 3; ++k) a[k] = std::uniform_real_distribution<float>(l.lower[k], l.upper[k])(rng);
  return a;
}

struct LimbPose {
  glm::quat upper{1, 0, 0, 0}, middle{1, 0, 0, 0}, lower{1, 0, 0, 0};
};

// Random angles inside every limit of the limb: a pose a correct solver can reproduce without breaking one.
LimbPose random_limb_pose(std::mt19937_64& rng, const Skeleton& s, const LimbChain& limb) {
  LimbPose p;
  p.upper = glm::quat_cast(rotation_from_limit_angles(uniform_in_limits(rng, s.limits[limb.upper])));
  const JointLimits& hinge = s.limits[limb.middle];
  p.middle = glm::angleAxis(std::uniform_real_distribution<float>(hinge.lower.x, hinge.upper.x)(rng),
                            glm::vec3(1, 0, 0));
  p.lower = glm::quat_cast(rotation_from_limit_angles(uniform_in_limits(rng, s.limits[limb.lower])));
  return p;
}

ReferencePose pose_with(const Skeleton& s, const LimbChain& limb, const LimbPose& p) {
  std::vector<glm::quat> r(s.joint_count(), glm::quat(1, 0, 0, 0));
  r[limb.upper] = p.upper, r[limb.middle] = p.middle, r[limb.lower] = p.lower;
  return fk_reference(s, r, glm::vec3(0.0f));
}
ReferencePose pose_with(const Skeleton& s, const LimbChain& limb, const LimbSolveResult& res) {
  return pose_with(s, limb, LimbPose{res.upper, res.middle, res.lower});
}

glm::vec3 position(const ReferencePose& p, int joint) { return glm::vec3(p.world[joint][3]); }
glm::quat orientation(const ReferencePose& p, int joint) { return glm::quat_cast(glm::mat3(p.world[joint])); }

float rotation_angle_between(const glm::quat& a, const glm::quat& b) {
  const glm::quat d = glm::conjugate(glm::normalize(a)) * glm::normalize(b);
  return 2.0f * std::atan2(glm::length(glm::vec3(d.x, d.y, d.z)), std::abs(d.w));
}

float excess(const JointLimits& l, const glm::quat& q) {
  return limit_violation(l, limit_angles(glm::mat3_cast(q)));
}

// Distance of point e from the swivel circle of a limb (upper at cu, bone lengths l1, l2) reaching for g
// (tech-brief 1.3): centre cu + l1 cos(a) n, radius l1 sin(a), in the plane normal to n.
// How far the middle joint e lies from the circle of positions that keep both bones' lengths between the upper
// joint cu and the goal g: the larger of the two spheres' misses. Rejected: the distance to the circle from its
// centre and radius, whose sqrt(1 - cos^2) turns float rounding into 0.2 mm for a nearly straight limb (the
// default leg is straight at rest).
float distance_from_circle(glm::vec3 cu, float l1, float l2, glm::vec3 g, glm::vec3 e) {
  return std::max(std::abs(glm::length(e - cu) - l1), std::abs(glm::length(g - e) - l2));
}

LimbSolveInput goal_of(const LimbChain& limb, const ReferencePose& ref, IkMode mode) {
  LimbSolveInput in;
  in.mode = mode;
  in.goal = position(ref, limb.lower);
  in.orientation = orientation(ref, limb.lower);
  in.pole = limb.pole;
  return in;
}

// ---- make_limbs --------------------------------------------------------------------------------------------

TEST(IkLimbs, ShippedSkeletonHasFourChainsWithTheDocumentedAxes) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  ASSERT_EQ(limbs.size(), static_cast<std::size_t>(kLimbCount));
  EXPECT_EQ(limbs[kLeftLeg].name, "l_leg");
  EXPECT_EQ(limbs[kRightArm].name, "r_arm");
  EXPECT_EQ(limbs[kLeftLeg].upper, s.find_joint("l_hip"));
  EXPECT_EQ(limbs[kLeftLeg].middle, s.find_joint("l_knee"));
  EXPECT_EQ(limbs[kLeftLeg].lower, s.find_joint("l_ankle"));
  EXPECT_EQ(limbs[kRightArm].upper, s.find_joint("r_shoulder"));
  EXPECT_EQ(limbs[kRightArm].lower, s.find_joint("r_wrist"));
  for (LimbIndex leg : {kLeftLeg, kRightLeg}) {
    EXPECT_EQ(limbs[leg].flexion_axis, glm::vec3(1, 0, 0));
    EXPECT_EQ(limbs[leg].pole, glm::vec3(0, 0, 1));
  }
  for (LimbIndex arm : {kLeftArm, kRightArm}) {
    EXPECT_EQ(limbs[arm].flexion_axis, glm::vec3(-1, 0, 0));
    EXPECT_EQ(limbs[arm].pole, glm::vec3(0, 0, -1));
  }
}

TEST(IkLimbs, MissingJointIsNamed) {
  Skeleton s = shipped();
  const int elbow = s.find_joint("l_elbow");
  s.joint_names[elbow] = "l_elbow_gone";
  s.source_joint_names[elbow] = "l_elbow_gone";
  try {
    make_limbs(s);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("l_elbow"), std::string::npos) << e.what();
  }
}

// ---- solve_limb on random reachable goals -------------------------------------------------------------------

void check_random_goals(IkMode mode, std::uint64_t seed) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  std::mt19937_64 rng(seed);
  for (const LimbChain& limb : limbs) {
    const glm::vec3 cu = s.centers[limb.upper];
    const float l1 = glm::length(s.centers[limb.middle] - cu);
    const float l2 = glm::length(s.centers[limb.lower] - s.centers[limb.middle]);
    float worst_pos = 0.0f, worst_rot = 0.0f, worst_limit = 0.0f, worst_circle = 0.0f;
    int moved = 0, bad_flags = 0;
    for (int i = 0; i < 10000; ++i) {
      const ReferencePose target = pose_with(s, limb, random_limb_pose(rng, s, limb));
      const LimbSolveInput in = goal_of(limb, target, mode);
      const LimbSolveResult res = solve_limb(s, limb, in);
      ASSERT_TRUE(finite(res)) << limb.name << " goal " << i;
      const ReferencePose got = pose_with(s, limb, res);
      const float err = glm::length(position(got, limb.lower) - in.goal);
      worst_pos = std::max(worst_pos, err);
      EXPECT_NEAR(res.position_error, err, 1e-6f);
      if (mode == IkMode::PositionOrientation)
        worst_rot = std::max(worst_rot, rotation_angle_between(orientation(got, limb.lower), in.orientation));
      else
        EXPECT_EQ(res.lower, glm::quat(1, 0, 0, 0)) << "position goals leave the lower joint at rest";
      float limit = excess(s.limits[limb.upper], res.upper) + excess(s.limits[limb.middle], res.middle);
      if (mode == IkMode::PositionOrientation) limit += excess(s.limits[limb.lower], res.lower);
      worst_limit = std::max(worst_limit, limit);
      worst_circle = std::max(worst_circle, distance_from_circle(cu, l1, l2, in.goal, position(got, limb.middle)));
      const std::uint32_t unwanted = kIkUnreachable | kIkLimitsInfeasible | kIkOrientationClamped | kIkInvalidInput;
      if ((res.flags & unwanted) != 0 || (res.flags & kIkReached) == 0) ++bad_flags;
      moved += (res.flags & kIkSwivelMoved) != 0;
    }
    EXPECT_LT(worst_pos, 1e-5f) << limb.name;
    EXPECT_LT(worst_rot, 1e-4f) << limb.name;
    EXPECT_LT(worst_limit, kLimitTolerance) << limb.name;
    EXPECT_LT(worst_circle, 1e-5f) << limb.name;
    EXPECT_EQ(bad_flags, 0) << limb.name << ": every goal is reachable within limits by construction";
    // Random poses mostly twist the upper joint away from the pole plane: the search must have run.
    EXPECT_GT(moved, 100) << limb.name;
  }
}

TEST(IkSolve, RandomReachablePositionGoals) { check_random_goals(IkMode::Position, 101); }
TEST(IkSolve, RandomReachablePositionOrientationGoals) { check_random_goals(IkMode::PositionOrientation, 202); }

// ---- the pole and the swivel --------------------------------------------------------------------------------

TEST(IkSolve, ZeroSwivelPutsKneesForwardAndElbowsBackInThePolePlane) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> swing(-0.35f, 0.35f), bend(0.1f, 0.8f);
  for (const LimbChain& limb : limbs) {
    const bool leg = limb.name.find("leg") != std::string::npos;
    int in_plane = 0;
    for (int i = 0; i < 500; ++i) {
      // Walking-like swing and bend: the requested swivel is feasible.
      LimbPose p;
      p.upper = glm::angleAxis(swing(rng), glm::vec3(1, 0, 0));
      p.middle = glm::angleAxis(leg ? bend(rng) : -bend(rng), glm::vec3(1, 0, 0));
      const LimbSolveInput in = goal_of(limb, pose_with(s, limb, p), IkMode::Position);
      const LimbSolveResult res = solve_limb(s, limb, in);
      ASSERT_EQ(res.flags & kIkSwivelMoved, 0u) << limb.name << ": walking poses need no swivel search";
      const glm::vec3 cu = s.centers[limb.upper];
      const glm::vec3 n = glm::normalize(in.goal - cu);
      const glm::vec3 e = position(pose_with(s, limb, res), limb.middle) - cu;
      const glm::vec3 off = e - glm::dot(e, n) * n;  // middle joint's offset from the upper->goal line
      const glm::vec3 u = glm::normalize(limb.pole - glm::dot(limb.pole, n) * n);
      EXPECT_GT(glm::dot(off, u), 0.005f) << limb.name << ": on the pole side";
      EXPECT_LT(std::abs(glm::dot(off, glm::cross(n, u))), 1e-5f) << limb.name << ": in the goal-pole plane";
      EXPECT_EQ(std::signbit(off.z), !leg) << limb.name << ": knees forward (+Z), elbows back (-Z)";
      ++in_plane;
    }
    EXPECT_EQ(in_plane, 500);
  }
}

TEST(IkSolve, SwivelOffsetTurnsTheMiddleJointAboutTheGoalAxis) {
  Skeleton s = shipped();
  for (JointLimits& l : s.limits) l.present = false;  // every swivel feasible
  const std::vector<LimbChain> limbs = make_limbs(s);
  const LimbChain& limb = limbs[kLeftArm];
  LimbPose p;
  p.upper = glm::angleAxis(-0.6f, glm::vec3(1, 0, 0));
  p.middle = glm::angleAxis(-1.0f, glm::vec3(1, 0, 0));
  LimbSolveInput in = goal_of(limb, pose_with(s, limb, p), IkMode::Position);
  const glm::vec3 cu = s.centers[limb.upper];
  const glm::vec3 n = glm::normalize(in.goal - cu);
  const glm::vec3 u = glm::normalize(limb.pole - glm::dot(limb.pole, n) * n);
  const glm::vec3 v = glm::cross(n, u);
  for (float offset : {-2.5f, -1.0f, 0.0f, 0.4f, 1.7f, 3.0f}) {
    in.swivel_offset = offset;
    const LimbSolveResult res = solve_limb(s, limb, in);
    EXPECT_EQ(res.flags & (kIkSwivelMoved | kIkLimitsInfeasible), 0u);
    EXPECT_NE(res.flags & kIkReached, 0u);
    const glm::vec3 e = position(pose_with(s, limb, res), limb.middle) - cu;
    const float measured = std::atan2(glm::dot(e, v), glm::dot(e, u));
    EXPECT_NEAR(std::remainder(measured - offset, 2.0f * 3.14159265f), 0.0f, 1e-4f) << offset;
    EXPECT_NEAR(res.swivel, offset, 1e-5f);
  }
}

TEST(IkSolve, InfeasibleSwivelMovesToTheNearestFeasibleOne) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  for (const LimbChain& limb : limbs) {
    LimbPose p;
    p.middle = glm::angleAxis(limb.name.find("leg") != std::string::npos ? 0.9f : -0.9f, glm::vec3(1, 0, 0));
    LimbSolveInput in = goal_of(limb, pose_with(s, limb, p), IkMode::Position);
    in.swivel_offset = 2.8f;  // knee pointing backwards / elbow forwards: needs a twist far past the limits
    const LimbSolveResult res = solve_limb(s, limb, in);
    ASSERT_TRUE(finite(res));
    EXPECT_NE(res.flags & kIkSwivelMoved, 0u) << limb.name;
    EXPECT_EQ(res.flags & kIkLimitsInfeasible, 0u) << limb.name;
    EXPECT_NE(res.flags & kIkReached, 0u) << limb.name;
    EXPECT_LT(excess(s.limits[limb.upper], res.upper), kLimitTolerance) << limb.name;
    const float taken = std::abs(std::remainder(res.swivel - in.swivel_offset, 2.0f * 3.14159265f));
    // Nearest: no swivel closer to the request (scanned every 0.005 rad) is feasible. A request the solver keeps
    // unmoved is feasible, which the limit check on its output confirms independently.
    int feasible_closer = 0;
    for (float d = -taken + 0.005f; d < taken - 0.005f; d += 0.005f) {
      LimbSolveInput probe = in;
      probe.swivel_offset = in.swivel_offset + d;
      const LimbSolveResult r = solve_limb(s, limb, probe);
      if ((r.flags & kIkSwivelMoved) == 0) {
        ++feasible_closer;
        EXPECT_LT(excess(s.limits[limb.upper], r.upper), kLimitTolerance);
      }
    }
    EXPECT_EQ(feasible_closer, 0) << limb.name << " moved by " << taken;
    // ...and just past the boundary the requested swivel is kept.
    LimbSolveInput past = in;
    past.swivel_offset = res.swivel + 0.01f * (std::remainder(res.swivel - in.swivel_offset, 6.2831853f) > 0 ? 1 : -1);
    EXPECT_EQ(solve_limb(s, limb, past).flags & kIkSwivelMoved, 0u) << limb.name;
  }
}

TEST(IkSolve, NoFeasibleSwivelTakesTheLeastViolationAndFlags) {
  Skeleton s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  const LimbChain& limb = limbs[kLeftLeg];
  // A hip that may barely move: a goal to the side needs abduction it does not have.
  s.limits[limb.upper].lower = glm::vec3(-0.05f);
  s.limits[limb.upper].upper = glm::vec3(0.05f);
  LimbSolveInput in;
  in.goal = s.centers[limb.upper] + glm::vec3(0.5f, -0.6f, 0.0f);
  in.pole = limb.pole;
  const LimbSolveResult res = solve_limb(s, limb, in);
  ASSERT_TRUE(finite(res));
  EXPECT_NE(res.flags & kIkLimitsInfeasible, 0u);
  EXPECT_NE(res.flags & kIkReached, 0u) << "the position still wins over the limits";
  // Least violation: no swivel on a fine scan does better (each probe's violation measured from its output).
  const float chosen = excess(s.limits[limb.upper], res.upper);
  EXPECT_GT(chosen, 0.0f);
  for (float phi = -3.14f; phi < 3.14f; phi += 0.01f) {
    LimbSolveInput probe = in;
    probe.swivel_offset = phi;
    const LimbSolveResult r = solve_limb(s, limb, probe);
    // A probe whose request is already the least violating point stays; others move to the same minimum.
    EXPECT_GE(excess(s.limits[limb.upper], r.upper) + 1e-3f, chosen) << phi;
  }
}

TEST(IkSolve, OrientationBeyondTheLowerLimitsIsClampedAndFlagged) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  const LimbChain& limb = limbs[kRightLeg];
  LimbPose p;
  p.middle = glm::angleAxis(0.5f, glm::vec3(1, 0, 0));
  LimbSolveInput in = goal_of(limb, pose_with(s, limb, p), IkMode::PositionOrientation);
  in.orientation = glm::angleAxis(2.5f, glm::normalize(glm::vec3(1, 1, 0)));  // far past the ankle's range
  const LimbSolveResult res = solve_limb(s, limb, in);
  ASSERT_TRUE(finite(res));
  EXPECT_NE(res.flags & kIkOrientationClamped, 0u);
  EXPECT_NE(res.flags & kIkReached, 0u);
  EXPECT_LT(excess(s.limits[limb.lower], res.lower), kLimitTolerance);
}

// ---- unreachable and degenerate goals -----------------------------------------------------------------------

void expect_clamped_along_goal(const Skeleton& s, const LimbChain& limb, const LimbSolveInput& in,
                               const LimbSolveResult& res) {
  ASSERT_TRUE(finite(res));
  EXPECT_NE(res.flags & kIkUnreachable, 0u);
  EXPECT_EQ(res.flags & kIkReached, 0u);
  const glm::vec3 cu = s.centers[limb.upper];
  const glm::vec3 eff = position(pose_with(s, limb, res), limb.lower);
  EXPECT_NEAR(res.position_error, glm::length(eff - in.goal), 1e-5f);
  EXPECT_GT(res.position_error, 1e-5f);
  const glm::vec3 to_goal = in.goal - cu;
  if (glm::length(to_goal) > 1e-6f) {
    EXPECT_LT(glm::length(glm::cross(glm::normalize(eff - cu), glm::normalize(to_goal))), 1e-4f)
        << "clamped along the goal direction";
  }
}

TEST(IkSolve, GoalBeyondReachIsClampedInsideAndFlagged) {
  const Skeleton& s = shipped();
  for (const LimbChain& limb : make_limbs(s)) {
    const float reach = glm::length(s.centers[limb.middle] - s.centers[limb.upper]) +
                        glm::length(s.centers[limb.lower] - s.centers[limb.middle]);
    for (glm::vec3 dir : {glm::vec3(0, -1, 0), glm::vec3(0.3f, -0.5f, 0.8f), glm::vec3(0, 1, 0)}) {
      LimbSolveInput in;
      in.goal = s.centers[limb.upper] + 1.5f * reach * glm::normalize(dir);
      in.pole = limb.pole;
      const LimbSolveResult res = solve_limb(s, limb, in);
      expect_clamped_along_goal(s, limb, in, res);
      const float got = glm::length(position(pose_with(s, limb, res), limb.lower) - s.centers[limb.upper]);
      // A straight rest limb (the default legs) stretches to exactly its bones' length; never past it.
      EXPECT_LE(got, reach * (1.0f + 1e-6f)) << limb.name;
      EXPECT_GT(got, 0.97f * reach) << limb.name << ": nearly stretched";
    }
  }
}

TEST(IkSolve, GoalInsideTheInnerReachOrOnTheUpperJointIsClamped) {
  const Skeleton& s = shipped();
  for (const LimbChain& limb : make_limbs(s)) {
    for (float dist : {0.05f, 0.0f}) {
      LimbSolveInput in;
      in.goal = s.centers[limb.upper] + dist * glm::vec3(0, -1, 0);
      in.pole = limb.pole;
      const LimbSolveResult res = solve_limb(s, limb, in);
      expect_clamped_along_goal(s, limb, in, res);
      EXPECT_LT(excess(s.limits[limb.middle], res.middle), kLimitTolerance) << "the hinge stays in its limits";
    }
  }
}

TEST(IkSolve, DistanceNeedingHyperextensionIsUnreachable) {
  // ISO 200x's leg is not straight at rest (its knee centre 6.8 cm in front of the hip-ankle line) and the knee
  // stops at -0.05 rad: its longest reach is shorter than L1 + L2. Goals between the two need the hinge outside
  // its limits. (The shipped default moves that knee onto the line; this is the 200x one.)
  Skeleton s = shipped();
  for (const char* knee : {"l_knee", "r_knee"}) {
    const std::int32_t j = s.find_joint(knee);
    s.centers[j] = glm::vec3(knee[0] == 'l' ? 0.104f : -0.104f, 0.4867f, 0.0308f);
    s.limits[j].lower.x = -0.05f;
  }
  const std::vector<LimbChain> limbs = make_limbs(s);
  const LimbChain& limb = limbs[kLeftLeg];
  LimbPose p;
  p.middle = glm::angleAxis(s.limits[limb.middle].lower.x, glm::vec3(1, 0, 0));
  const glm::vec3 cu = s.centers[limb.upper];
  const float longest = glm::length(position(pose_with(s, limb, p), limb.lower) - cu);
  const float l12 = glm::length(s.centers[limb.middle] - cu) +
                    glm::length(s.centers[limb.lower] - s.centers[limb.middle]);
  ASSERT_LT(longest + 0.002f, l12);
  LimbSolveInput in;
  in.goal = cu + 0.5f * (longest + l12) * glm::normalize(glm::vec3(0.05f, -1, 0.1f));
  in.pole = limb.pole;
  const LimbSolveResult res = solve_limb(s, limb, in);
  expect_clamped_along_goal(s, limb, in, res);
  EXPECT_NEAR(limit_angles(glm::mat3_cast(res.middle)).x, s.limits[limb.middle].lower.x, 1e-3f);
  // The longest reach itself is reachable.
  in.goal = cu + longest * glm::normalize(glm::vec3(0.05f, -1, 0.1f));
  EXPECT_NE(solve_limb(s, limb, in).flags & kIkReached, 0u);
}

// A three-joint chain hanging straight down from (0, 1, 0), no limits: upper -> middle -> lower.
Skeleton straight_chain(glm::vec3 middle, glm::vec3 lower) {
  Skeleton s;
  s.name = "chain";
  const char* names[4] = {"HumanoidRoot", "l_hip", "l_knee", "l_ankle"};
  const glm::vec3 centers[4] = {{0, 1.2f, 0}, {0, 1, 0}, middle, lower};
  for (int j = 0; j < 4; ++j) {
    s.joint_names.push_back(names[j]);
    s.source_joint_names.push_back(names[j]);
    s.parents.push_back(j - 1);
    s.centers.push_back(centers[j]);
    s.limits.emplace_back();
    s.stiffness.emplace_back(1.0f);
  }
  return s;
}
LimbChain chain_limb() { return LimbChain{"l_leg", 1, 2, 3, {1, 0, 0}, {0, 0, 1}}; }

TEST(IkSolve, StraightLimbAtFullReachAndPoleAlongTheGoal) {
  const Skeleton s = straight_chain({0, 0.5f, 0}, {0, 0, 0});
  const LimbChain limb = chain_limb();
  for (glm::vec3 dir : {glm::vec3(0, -1, 0), glm::vec3(0, 0, 1), glm::vec3(0.6f, 0.0f, -0.8f), glm::vec3(0, 1, 0)}) {
    for (glm::vec3 pole : {glm::vec3(0, 0, 1), dir, -dir, glm::vec3(0.0f)}) {
      LimbSolveInput in;
      in.goal = glm::vec3(0, 1, 0) + 1.0f * dir;  // exactly L1 + L2: the straight limb
      in.pole = pole;
      const LimbSolveResult res = solve_limb(s, limb, in);
      ASSERT_TRUE(finite(res));
      EXPECT_NE(res.flags & kIkReached, 0u);
      EXPECT_LT(glm::length(position(pose_with(s, limb, res), limb.lower) - in.goal), 1e-5f);
      // A bent goal with the pole along the goal direction: the fallback projection axis still gives a solution.
      in.goal = glm::vec3(0, 1, 0) + 0.6f * dir;
      in.pole = dir;
      const LimbSolveResult bent = solve_limb(s, limb, in);
      ASSERT_TRUE(finite(bent));
      EXPECT_NE(bent.flags & kIkReached, 0u);
      EXPECT_LT(glm::length(position(pose_with(s, limb, bent), limb.lower) - in.goal), 1e-5f);
    }
  }
}

TEST(IkSolve, PoleParallelToGoalOnTheShippedArm) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  const LimbChain& limb = limbs[kLeftArm];
  LimbPose p;
  p.middle = glm::angleAxis(-1.2f, glm::vec3(1, 0, 0));
  LimbSolveInput in = goal_of(limb, pose_with(s, limb, p), IkMode::Position);
  in.pole = in.goal - s.centers[limb.upper];
  const LimbSolveResult res = solve_limb(s, limb, in);
  ASSERT_TRUE(finite(res));
  EXPECT_NE(res.flags & kIkReached, 0u);
}

TEST(IkSolve, ZeroLengthBonesStayFinite) {
  const LimbChain limb = chain_limb();
  // Upper bone of zero length: the reach is exactly L2 whatever the hinge does.
  {
    const Skeleton s = straight_chain({0, 1, 0}, {0, 0.5f, 0});
    LimbSolveInput in;
    in.goal = glm::vec3(0.3f, 1.4f, 0.0f);  // |goal - upper| = 0.5
    const LimbSolveResult res = solve_limb(s, limb, in);
    ASSERT_TRUE(finite(res));
    EXPECT_NE(res.flags & kIkReached, 0u);
    in.goal = glm::vec3(0.1f, 1.0f, 0.0f);
    const LimbSolveResult far = solve_limb(s, limb, in);
    ASSERT_TRUE(finite(far));
    EXPECT_NE(far.flags & kIkUnreachable, 0u);
  }
  // Lower bone of zero length.
  {
    const Skeleton s = straight_chain({0, 0.5f, 0}, {0, 0.5f, 0});
    LimbSolveInput in;
    in.goal = glm::vec3(0.0f, 1.0f, 0.5f);
    const LimbSolveResult res = solve_limb(s, limb, in);
    ASSERT_TRUE(finite(res));
    EXPECT_NE(res.flags & kIkReached, 0u);
    EXPECT_LT(glm::length(position(pose_with(s, limb, res), limb.lower) - in.goal), 1e-5f);
  }
  // Both zero: the effector cannot move; any goal but the upper joint is unreachable.
  {
    const Skeleton s = straight_chain({0, 1, 0}, {0, 1, 0});
    LimbSolveInput in;
    in.goal = glm::vec3(0.0f, 0.5f, 0.0f);
    const LimbSolveResult res = solve_limb(s, limb, in);
    ASSERT_TRUE(finite(res));
    EXPECT_NE(res.flags & kIkUnreachable, 0u);
    EXPECT_NEAR(res.position_error, 0.5f, 1e-5f);
  }
}

TEST(IkSolve, NonFiniteInputsAreFlaggedNeverPropagated) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  const LimbChain& limb = limbs[kRightArm];
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (glm::vec3 goal : {glm::vec3(nan, 0, 0), glm::vec3(0, inf, 0), glm::vec3(0, 0, -inf)}) {
    LimbSolveInput in;
    in.goal = goal;
    const LimbSolveResult res = solve_limb(s, limb, in);
    ASSERT_TRUE(finite(res));
    EXPECT_NE(res.flags & kIkInvalidInput, 0u);
    EXPECT_EQ(res.flags & kIkReached, 0u);
    EXPECT_EQ(res.upper, glm::quat(1, 0, 0, 0));
  }
  // A usable goal with a broken pole, swivel or orientation: solved, flagged.
  LimbPose p;
  p.middle = glm::angleAxis(-0.8f, glm::vec3(1, 0, 0));
  const LimbSolveInput good = goal_of(limb, pose_with(s, limb, p), IkMode::PositionOrientation);
  LimbSolveInput in = good;
  in.pole = glm::vec3(nan, 0, 1);
  LimbSolveResult res = solve_limb(s, limb, in);
  ASSERT_TRUE(finite(res));
  EXPECT_EQ(res.flags & (kIkInvalidInput | kIkReached), kIkInvalidInput | kIkReached);
  in = good;
  in.swivel_offset = inf;
  res = solve_limb(s, limb, in);
  ASSERT_TRUE(finite(res));
  EXPECT_EQ(res.flags & (kIkInvalidInput | kIkReached), kIkInvalidInput | kIkReached);
  in = good;
  in.orientation = glm::quat(nan, 0, 0, 0);
  res = solve_limb(s, limb, in);
  ASSERT_TRUE(finite(res));
  EXPECT_EQ(res.flags & (kIkInvalidInput | kIkReached), kIkInvalidInput | kIkReached);
  in.orientation = glm::quat(0, 0, 0, 0);
  res = solve_limb(s, limb, in);
  ASSERT_TRUE(finite(res));
  EXPECT_NE(res.flags & kIkInvalidInput, 0u);
}

TEST(IkSolve, OffModeReturnsRestUnflagged) {
  const Skeleton& s = shipped();
  LimbSolveInput in;
  in.mode = IkMode::Off;
  in.goal = glm::vec3(1, 2, 3);
  const LimbSolveResult res = solve_limb(s, make_limbs(s)[kLeftLeg], in);
  EXPECT_EQ(res.flags, 0u);
  EXPECT_EQ(res.upper, glm::quat(1, 0, 0, 0));
  EXPECT_EQ(res.middle, glm::quat(1, 0, 0, 0));
}

// ---- the system ---------------------------------------------------------------------------------------------

glm::vec3 lane_position(const WalkerLanes& lanes, std::size_t joint, std::size_t w) {
  glm::vec3 p;
  for (int r = 0; r < 3; ++r) p[r] = lanes.world[(joint * kAffineFloats + 9 + r) * lanes.stride + w];
  return p;
}
glm::quat lane_orientation(const WalkerLanes& lanes, std::size_t joint, std::size_t w) {
  glm::mat3 m;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) m[c][r] = lanes.world[(joint * kAffineFloats + c * 3 + r) * lanes.stride + w];
  return glm::quat_cast(m);
}

struct SystemCase {
  std::unique_ptr<SoaTable> table;
  std::vector<std::vector<glm::vec3>> goals;    // [walker][limb], humanoid space
  std::vector<std::vector<glm::quat>> targets;  // [walker][limb], the lower joint's frame
};

// Walkers with random root, pelvis and spine rotations and root translations; limb goals made by FK of random
// limb poses inside the limits. Legs get position + orientation goals, arms position goals; odd walkers give the
// pole explicitly (the rig's pole carried into humanoid space), even ones leave it zero.
SystemCase make_system_case(std::size_t walkers, std::uint64_t seed) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  const auto joints = static_cast<std::uint32_t>(s.joint_count());
  SystemCase c;
  c.table = make_walker_table("ik", joints);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (std::size_t w = 0; w < walkers; ++w) {
    const std::uint32_t block = c.table->add(Entity{static_cast<std::uint32_t>(w + 1), 1});
    std::vector<glm::quat> pose(joints, glm::quat(1, 0, 0, 0));
    pose[0] = glm::angleAxis(3.0f * u(rng), glm::normalize(glm::vec3(u(rng), u(rng), u(rng)) + glm::vec3(0, 0.01f, 0)));
    for (const char* name : {"sacroiliac", "vl5", "vt6", "vt1", "l_sternoclavicular", "r_acromioclavicular"}) {
      const int j = s.find_joint(name);
      pose[j] = glm::quat_cast(rotation_from_limit_angles(uniform_in_limits(rng, s.limits[j])));
    }
    for (const LimbChain& limb : limbs) {
      const LimbPose p = random_limb_pose(rng, s, limb);
      pose[limb.upper] = p.upper, pose[limb.middle] = p.middle, pose[limb.lower] = p.lower;
    }
    const glm::vec3 root(u(rng), 0.3f * u(rng), u(rng));
    const ReferencePose ref = fk_reference(s, pose, root);
    c.goals.emplace_back();
    c.targets.emplace_back();
    for (std::size_t k = 0; k < limbs.size(); ++k) {
      const LimbChain& limb = limbs[k];
      const glm::vec3 g = position(ref, limb.lower);
      const glm::quat o = orientation(ref, limb.lower);
      c.goals.back().push_back(g);
      c.targets.back().push_back(o);
      auto goal = [&](std::uint32_t comp) -> float& {
        return c.table->f32(kWalkerIkGoal, static_cast<std::uint32_t>(k * kIkGoalFloats + comp))[block];
      };
      goal(kGoalPx) = g.x, goal(kGoalPy) = g.y, goal(kGoalPz) = g.z;
      goal(kGoalQx) = o.x, goal(kGoalQy) = o.y, goal(kGoalQz) = o.z, goal(kGoalQw) = o.w;
      c.table->i32(kWalkerIkMode, static_cast<std::uint32_t>(k))[block] =
          static_cast<std::int32_t>(k < 2 ? IkMode::PositionOrientation : IkMode::Position);
      if (w % 2 == 1) {
        const glm::vec3 pole = glm::mat3(ref.world[s.parents[limb.upper]]) * limb.pole;
        goal(kGoalPoleX) = pole.x, goal(kGoalPoleY) = pole.y, goal(kGoalPoleZ) = pole.z;
      }
      // The solver must not read the pose it is asked to find: scramble the limb's rotations.
      pose[limb.upper] = glm::angleAxis(1.0f, glm::vec3(0, 1, 0));
      pose[limb.middle] = glm::quat(1, 0, 0, 0);
      pose[limb.lower] = glm::angleAxis(-0.5f, glm::vec3(0, 0, 1));
    }
    for (std::uint32_t j = 0; j < joints; ++j)
      for (std::uint32_t k = 0; k < 4; ++k) {
        const float comp[4] = {pose[j].x, pose[j].y, pose[j].z, pose[j].w};
        c.table->f32(kWalkerLocalRotation, j * 4 + k)[block] = comp[k];
      }
    for (std::uint32_t k = 0; k < 3; ++k) c.table->f32(kWalkerRootTranslation, k)[block] = root[k];
  }
  return c;
}

TEST(IkSystem, GoalsReachedThroughPosedParentsAfterFk) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  SystemCase c = make_system_case(37, 9);
  const WalkerLanes lanes = walker_lanes(*c.table, static_cast<std::uint32_t>(s.joint_count()));
  ASSERT_TRUE(make_ik_job(s, limbs, *c.table).run());
  ASSERT_TRUE(make_fk_job(s, *c.table).run());
  for (std::size_t w = 0; w < lanes.count; ++w) {
    for (std::size_t k = 0; k < limbs.size(); ++k) {
      const glm::vec3 got = lane_position(lanes, limbs[k].lower, w);
      EXPECT_LT(glm::length(got - c.goals[w][k]), 1e-5f) << "walker " << w << " " << limbs[k].name;
      if (k < 2) {
        EXPECT_LT(rotation_angle_between(lane_orientation(lanes, limbs[k].lower, w), c.targets[w][k]), 1e-4f)
            << "walker " << w << " " << limbs[k].name;
      }
      const std::uint32_t flags = lanes.ik_flags[k * lanes.stride + w];
      const float error = lanes.ik_result[(k * kIkResultFloats) * lanes.stride + w];
      EXPECT_NE(flags & kIkReached, 0u) << "walker " << w << " " << limbs[k].name;
      EXPECT_LT(error, 1e-5f);
    }
  }
}

TEST(IkSystem, OffLimbsAndBrokenGoalsKeepTheirRotations) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  SystemCase c = make_system_case(3, 4);
  c.table->i32(kWalkerIkMode, kRightArm)[0] = static_cast<std::int32_t>(IkMode::Off);
  c.table->f32(kWalkerIkGoal, kLeftArm * kIkGoalFloats + kGoalPx)[1] = std::numeric_limits<float>::quiet_NaN();
  const WalkerLanes lanes = walker_lanes(*c.table, static_cast<std::uint32_t>(s.joint_count()));
  auto rot = [&](int joint, std::size_t w) {
    glm::vec4 q;
    for (int k = 0; k < 4; ++k) q[k] = lanes.local_rotation[(joint * 4 + k) * lanes.stride + w];
    return q;
  };
  const glm::vec4 off_before = rot(limbs[kRightArm].upper, 0), broken_before = rot(limbs[kLeftArm].upper, 1);
  ASSERT_TRUE(make_ik_job(s, limbs, *c.table).run());
  EXPECT_EQ(rot(limbs[kRightArm].upper, 0), off_before);
  EXPECT_EQ(rot(limbs[kLeftArm].upper, 1), broken_before);
  EXPECT_EQ(lanes.ik_flags[kRightArm * lanes.stride + 0], 0u);
  EXPECT_EQ(lanes.ik_result[(kRightArm * kIkResultFloats) * lanes.stride + 0], 0.0f);
  EXPECT_EQ(lanes.ik_flags[kLeftArm * lanes.stride + 1], static_cast<std::uint32_t>(kIkInvalidInput));
  const std::uint32_t leg_flags = lanes.ik_flags[kLeftLeg * lanes.stride + 1];
  EXPECT_NE(leg_flags & kIkReached, 0u) << "the other limbs of that walker still solve";
}

TEST(IkSystem, OutputIdenticalForOneAndTwoThreads) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  for (std::size_t walkers : {37u, 301u}) {
    SystemCase a = make_system_case(walkers, 21);
    SystemCase b = make_system_case(walkers, 21);
    const auto joints = static_cast<std::uint32_t>(s.joint_count());
    {
      tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      ASSERT_TRUE(make_ik_job(s, limbs, *a.table).run());
    }
    {
      tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
      ASSERT_TRUE(make_ik_job(s, limbs, *b.table).run());
    }
    for (std::uint32_t k = 0; k < joints * 4; ++k) {
      const auto x = a.table->f32(kWalkerLocalRotation, k), y = b.table->f32(kWalkerLocalRotation, k);
      ASSERT_EQ(std::memcmp(x.data(), y.data(), x.size_bytes()), 0) << "rotation component " << k;
    }
    for (std::uint32_t k = 0; k < kIkLimbs * kIkResultFloats; ++k) {
      const auto x = a.table->f32(kWalkerIkResult, k), y = b.table->f32(kWalkerIkResult, k);
      ASSERT_EQ(std::memcmp(x.data(), y.data(), x.size_bytes()), 0) << "result component " << k;
    }
    for (std::uint32_t k = 0; k < kIkLimbs; ++k) {
      const auto x = a.table->u32(kWalkerIkFlags, k), y = b.table->u32(kWalkerIkFlags, k);
      ASSERT_EQ(std::memcmp(x.data(), y.data(), x.size_bytes()), 0) << "flags of limb " << k;
    }
  }
}

// validate() rejects each missing or mismatched input, and run() then writes nothing.
TEST(IkJob, JobValidity) {
  const Skeleton& s = shipped();
  const std::vector<LimbChain> limbs = make_limbs(s);
  SystemCase c = make_system_case(5, 8);
  SoaTable& table = *c.table;
  const IkJob good = make_ik_job(s, limbs, table);
  test::fill_sentinel(table, kWalkerLocalRotation);
  test::fill_sentinel(table, kWalkerIkResult);
  test::fill_sentinel(table, kWalkerIkFlags);
  auto untouched = [&] {
    return test::holds_sentinel(table, kWalkerLocalRotation) && test::holds_sentinel(table, kWalkerIkResult) &&
           test::holds_sentinel(table, kWalkerIkFlags);
  };
  using namespace test;
  IkJob j = good;
  j.skeleton = nullptr;
  expect_refused(j, "no skeleton", untouched);
  j = good, j.limbs = {};
  expect_refused(j, "no limbs", untouched);
  std::vector<LimbChain> five = limbs;
  five.push_back(limbs[0]);
  j = good, j.limbs = five;
  expect_refused(j, "more limbs than goal slots", untouched);
  std::vector<LimbChain> broken = limbs;
  broken[1].lower = static_cast<std::int32_t>(s.joint_count());
  j = good, j.limbs = broken;
  expect_refused(j, "a limb joint outside the skeleton", untouched);
  broken = limbs;
  std::swap(broken[2].middle, broken[2].lower);
  j = good, j.limbs = broken;
  expect_refused(j, "a limb that is not a chain", untouched);
  j = good, j.ik_goal = with_components(good.ik_goal, kIkLimbs * kIkGoalFloats + 1);
  expect_refused(j, "goals of another layout", untouched);
  j = good, j.ik_mode = without_base(good.ik_mode);
  expect_refused(j, "no modes", untouched);
  j = good, j.root_translation = with_count(good.root_translation, 4);
  expect_refused(j, "root translation of fewer walkers", untouched);
  j = good, j.local_rotation = with_components(good.local_rotation, 4 * 3);
  expect_refused(j, "rotations of another joint count", untouched);
  j = good, j.ik_error = with_stride(good.ik_error, 3);
  expect_refused(j, "error stride below the walker count", untouched);
  j = good, j.ik_flags = without_base(good.ik_flags);
  expect_refused(j, "no flags output", untouched);
  // An output over an input's memory: the error column written over the goals.
  j = good, j.ik_error.base = const_cast<float*>(good.ik_goal.base);
  expect_refused(j, "error output aliasing the goals", untouched);

  EXPECT_TRUE(good.validate());
  EXPECT_TRUE(good.run());
  EXPECT_FALSE(test::holds_sentinel(table, kWalkerIkFlags));
}

}  // namespace
}  // namespace strata
