// The walk following a steered agent: agent_move -> locomotion (agent mode) -> IK -> FK on the shipped skeleton,
// with the agent's wished velocity scripted (no avoidance or navigation), measured from the FK output.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "io/hanim_loader.h"
#include "scene/crowd.h"
#include "scene/spawn.h"
#include "systems/agent_move.h"
#include "systems/animation_sample.h"
#include "systems/fk.h"
#include "systems/gait_metrics.h"
#include "systems/ik.h"
#include "systems/job.h"
#include "systems/locomotion.h"

namespace strata {
namespace {

constexpr float kPi = 3.14159265358979f;

// One agent-following walker standing at `at` facing `heading`, as scene/crowd_agents.cpp spawns them.
struct AgentWalker {
  std::unique_ptr<Crowd> crowd = std::make_unique<Crowd>(to_rig(load_default_humanoid()));
  Entity walker;
  AgentMoveParameters move;

  explicit AgentWalker(glm::vec2 at = {0.0f, 0.0f}, float heading = 0.0f, float height = 1.72f) {
    Crowd& c = *crowd;
    c.motion.source = MotionSource::Walk;
    c.widen_for_agents();
    walker = spawn_clip_walker(c, glm::vec3(at.x, 0.0f, at.y), heading, 0.0f, 1.0f, kRestPose);
    SoaTable& t = table();
    t.f32(kWalkerAgent, kAgentPx)[0] = at.x;
    t.f32(kWalkerAgent, kAgentPz)[0] = at.y;
    t.f32(kWalkerAgent, kAgentHeading)[0] = heading;
    t.f32(kWalkerAgent, kAgentRadius)[0] = 0.3f;
    t.f32(kWalkerAgent, kAgentPrefSpeed)[0] = 1.3f;
    t.f32(kWalkerAgent, kAgentGoalRadius)[0] = 0.5f;
    t.f32(kWalkerGait, kGaitHeight)[0] = height;
    t.f32(kWalkerGait, kGaitCadence)[0] = c.motion.style.agent_min_cadence;
    t.f32(kWalkerGait, kGaitCadenceTarget)[0] = c.motion.style.agent_min_cadence;
    t.f32(kWalkerGait, kGaitIdle)[0] = 1.0f;
    move.turn_rate = c.motion.style.turn_rate;
    move.turn_in_place_rate = c.motion.style.turn_in_place_rate;
    move.acceleration = c.motion.style.agent_acceleration;
    move.braking = c.motion.style.agent_braking;
    run_or_throw(make_start_walking_job(*c.motion.locomotion, c.motion.paths, t, 0, c.motion.style, true), "start");
    run_or_throw(make_ik_job(c.rig().skeleton, c.motion.locomotion->limbs, t), "ik");
    run_or_throw(make_fk_job(c.rig().skeleton, t), "fk");
  }
  SoaTable& table() { return crowd->world.table(crowd->world.location(walker).table); }
  float agent(std::uint32_t c) { return table().f32(kWalkerAgent, c)[0]; }
  float gait(std::uint32_t c) { return table().f32(kWalkerGait, c)[0]; }

  // One frame with the agent wishing to move at `wish` (m/s, ground x and z); `before_locomotion` may change the
  // walker's columns between agent_move and locomotion (what the last IK run reported, say).
  void frame(glm::vec2 wish, float dt, const std::function<void(SoaTable&)>& before_locomotion = {}) {
    Crowd& c = *crowd;
    SoaTable& t = table();
    // As navigation does: the wish goes through what the body can follow; no one to avoid, so avoidance would
    // return it unchanged.
    const glm::vec2 pref = followable_velocity(wish, t.f32(kWalkerAgent, kAgentHeading)[0],
                                               std::hypot(t.f32(kWalkerAgent, kAgentVx)[0], t.f32(kWalkerAgent, kAgentVz)[0]),
                                               move, dt);
    t.f32(kWalkerAgent, kAgentTargetX)[0] = t.f32(kWalkerAgent, kAgentPx)[0] + 10.0f * wish.x;
    t.f32(kWalkerAgent, kAgentTargetZ)[0] = t.f32(kWalkerAgent, kAgentPz)[0] + 10.0f * wish.y;
    t.f32(kWalkerAgent, kAgentOrcaVx)[0] = t.f32(kWalkerAgent, kAgentPrefVx)[0] = pref.x;
    t.f32(kWalkerAgent, kAgentOrcaVz)[0] = t.f32(kWalkerAgent, kAgentPrefVz)[0] = pref.y;
    run_or_throw(make_agent_move_job(t, dt, move), "agent_move");
    if (before_locomotion) before_locomotion(t);
    run_or_throw(make_locomotion_job(*c.motion.locomotion, c.motion.paths, t, dt, c.motion.style, true), "locomotion");
    run_or_throw(make_ik_job(c.rig().skeleton, c.motion.locomotion->limbs, t), "ik");
    run_or_throw(make_fk_job(c.rig().skeleton, t), "fk");
  }
  // A world joint of the walker after the last frame.
  glm::vec3 joint(std::int32_t j) {
    const WalkerLanes l = walker_lanes(table(), crowd->joint_count());
    const Placement p = placement_of(l, 0);
    const std::size_t s = l.stride;
    const float* w = l.world + static_cast<std::size_t>(j) * kAffineFloats * s;
    return p.point({w[9 * s], w[10 * s], w[11 * s]});
  }
};

struct WalkResult {
  GaitReport gait;
  bool finite = true;
};

// `seconds` of frames with the wish given by `script(t)`, measured.
WalkResult walk(AgentWalker& w, float seconds, const std::function<glm::vec2(float)>& script, GaitMetrics& metrics,
         float& clock, float dt = 1.0f / 60.0f) {
  WalkResult r;
  const auto frames = static_cast<int>(seconds / dt + 0.5f);
  for (int f = 0; f < frames; ++f) {
    w.frame(script(clock), dt);
    clock += dt;
    metrics.observe(walker_lanes(w.table(), w.crowd->joint_count()), w.crowd->motion.paths, dt);
    for (std::uint32_t c = 0; c < kAgentFloats; ++c) r.finite = r.finite && std::isfinite(w.agent(c));
  }
  r.gait = metrics.report();
  return r;
}

TEST(AgentWalk, StandsStillWhenItDoesNotWantToMove) {
  AgentWalker w;
  const LocomotionRig& rig = *w.crowd->motion.locomotion;
  const glm::vec3 left0 = w.joint(rig.limbs[kLeftLeg].lower), right0 = w.joint(rig.limbs[kRightLeg].lower);
  GaitMetrics metrics(w.crowd->rig().skeleton, rig, w.crowd->motion.style);
  float clock = 0.0f;
  const WalkResult r = walk(w, 3.0f, [](float) { return glm::vec2(0.0f); }, metrics, clock);
  EXPECT_TRUE(r.finite);
  EXPECT_EQ(r.gait.nan_count, 0u);
  EXPECT_FLOAT_EQ(w.gait(kGaitIdle), 1.0f);
  EXPECT_FLOAT_EQ(w.agent(kAgentPx), 0.0f);
  EXPECT_FLOAT_EQ(w.agent(kAgentPz), 0.0f);
  // Feet stay where they stand (the weight shift moves the pelvis, not the feet).
  EXPECT_LT(glm::length(w.joint(rig.limbs[kLeftLeg].lower) - left0), 1e-3f);
  EXPECT_LT(glm::length(w.joint(rig.limbs[kRightLeg].lower) - right0), 1e-3f);
  // Side by side: the ankles are level and at the same depth along the heading (+Z).
  EXPECT_LT(std::abs(left0.z - right0.z), 0.05f);
  EXPECT_NEAR(std::abs(left0.x - right0.x), 0.2f, 0.1f) << "hip-width apart";
}

TEST(AgentWalk, StartsWalksTurnsStopsAndStartsAgainWithoutSliding) {
  AgentWalker w;
  const LocomotionRig& rig = *w.crowd->motion.locomotion;
  float clock = 0.0f;
  // Each leg of the route measured on its own: walk off +Z, turn to +X, stop, turn round on the spot to -X and
  // walk off again.
  auto leg_of_route = [&](float seconds, glm::vec2 wish) {
    GaitMetrics metrics(w.crowd->rig().skeleton, rig, w.crowd->motion.style);
    return walk(w, seconds, [wish](float) { return wish; }, metrics, clock);
  };
  const WalkResult forward = leg_of_route(4.0f, {0.0f, 1.3f});
  EXPECT_FLOAT_EQ(w.gait(kGaitIdle), 0.0f) << "walking";
  EXPECT_GT(w.agent(kAgentPz), 3.0f) << "it accelerated and walked";
  EXPECT_NEAR(w.agent(kAgentHeading), 0.0f, 0.02f);
  const WalkResult turn = leg_of_route(3.0f, {1.3f, 0.0f});
  EXPECT_NEAR(w.agent(kAgentHeading), 0.5f * kPi, 0.02f) << "it turned to face +X";
  const float x_before_stop = w.agent(kAgentPx);
  const WalkResult stop = leg_of_route(3.0f, {0.0f, 0.0f});
  EXPECT_FLOAT_EQ(w.gait(kGaitIdle), 1.0f) << "standing after stopping";
  EXPECT_LT(w.agent(kAgentPx) - x_before_stop, 1.5f) << "braked within a couple of steps";
  const glm::vec3 l = w.joint(rig.limbs[kLeftLeg].lower), r = w.joint(rig.limbs[kRightLeg].lower);
  EXPECT_LT(std::abs(l.x - r.x), 0.17f) << "feet together along the heading (+X) after stopping";
  const WalkResult back = leg_of_route(4.0f, {-1.2f, 0.0f});
  EXPECT_NEAR(w.agent(kAgentHeading), -0.5f * kPi, 0.02f) << "turned round to face -X";
  EXPECT_FLOAT_EQ(w.gait(kGaitIdle), 0.0f);
  for (const WalkResult* part : {&forward, &turn, &stop, &back}) {
    const GaitReport& g = part->gait;
    EXPECT_TRUE(part->finite);
    EXPECT_EQ(g.nan_count, 0u);
    EXPECT_LT(g.ik_position_error_max_m, 1e-4);
    // Stopping leaves the toe tip 1.6 mm off where it rolled (the ankle at its plantarflexion limit as the
    // trailing heel comes down); everything else holds the walk's 1 mm.
    EXPECT_LT(g.foot_slide_mm_max, part == &stop ? 2.0 : 1.0)
        << "ball " << g.foot_slide_ball_mm_max << " ankle " << g.foot_slide_ankle_mm_max << " heel "
        << g.foot_slide_heel_mm_max << " tip " << g.foot_slide_tip_mm_max;
  }
  EXPECT_GT(back.gait.strides, 2u);
}

TEST(AgentWalk, SlowAgentsTakeShorterStepsNotSlowMotion) {
  AgentWalker w;
  GaitMetrics metrics(w.crowd->rig().skeleton, *w.crowd->motion.locomotion, w.crowd->motion.style);
  float clock = 0.0f;
  walk(w, 6.0f, [](float) { return glm::vec2(0.0f, 0.4f); }, metrics, clock);
  EXPECT_GE(w.gait(kGaitCadence), w.crowd->motion.style.agent_min_cadence - 1e-3f);
  EXPECT_NEAR(std::hypot(w.agent(kAgentVx), w.agent(kAgentVz)), 0.4f, 1e-3f);
  const GaitReport g = metrics.report();
  EXPECT_LT(g.foot_slide_mm_max, 1.0);
  // Steps: distance covered per stride is what 0.4 m/s at >= 80 steps/min allows, not the formula's step.
  EXPECT_LT(g.stride_length_mean_m, 0.65);
  EXPECT_GT(g.stride_length_mean_m, 0.4);
}

// A stance leg whose goal IK could not reach in the last frame (the body pushed away from the planted foot) makes
// the gait phase run stance_hurry times faster, so that stance ends sooner; the same walker with the leg reached
// keeps its pace. Two walkers on the same script, one told its stance leg missed.
TEST(AgentWalk, AStanceLegOutOfReachHurriesItsStep) {
  AgentWalker plain, pushed;
  GaitMetrics metrics_plain(plain.crowd->rig().skeleton, *plain.crowd->motion.locomotion, plain.crowd->motion.style);
  GaitMetrics metrics_pushed(pushed.crowd->rig().skeleton, *pushed.crowd->motion.locomotion, pushed.crowd->motion.style);
  float clock_plain = 0.0f, clock_pushed = 0.0f;
  const auto forward = [](float) { return glm::vec2(0.0f, 1.2f); };
  walk(plain, 1.5f, forward, metrics_plain, clock_plain);
  walk(pushed, 1.5f, forward, metrics_pushed, clock_pushed);
  ASSERT_EQ(plain.gait(kGaitPhase), pushed.gait(kGaitPhase));
  ASSERT_LE(plain.gait(kGaitIdle), 0.0f) << "walking, not standing";
  int stance = -1;
  for (int leg = 0; leg < 2 && stance < 0; ++leg)
    if (plain.gait(kGaitLegs + static_cast<std::uint32_t>(leg) * kLegFloats + kLegSwinging) < 0.5f) stance = leg;
  ASSERT_GE(stance, 0);
  const float before = plain.gait(kGaitPhase);
  const float dt = 1.0f / 60.0f;
  plain.frame({0.0f, 1.2f}, dt);
  pushed.frame({0.0f, 1.2f}, dt, [&](SoaTable& t) {
    t.u32(kWalkerIkFlags, static_cast<std::uint32_t>(stance))[0] = kIkUnreachable;
  });
  const auto advance = [&](float after) { return after - before + (after < before ? 1.0f : 0.0f); };
  const float normal = advance(plain.gait(kGaitPhase)), hurried = advance(pushed.gait(kGaitPhase));
  ASSERT_GT(normal, 0.0f);
  EXPECT_NEAR(hurried / normal, plain.crowd->motion.style.stance_hurry, 1e-3f);
}

TEST(AgentWalk, AgentMoveRefusesNonFiniteVelocities) {
  AgentWalker w;
  SoaTable& t = w.table();
  t.f32(kWalkerAgent, kAgentOrcaVx)[0] = std::nanf("");
  const float before = w.agent(kAgentPx);
  EXPECT_FALSE(make_agent_move_job(t, 1.0f / 60.0f, w.move).run());
  EXPECT_EQ(w.agent(kAgentPx), before);
}

}  // namespace
}  // namespace strata
