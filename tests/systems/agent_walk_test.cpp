// The walk following a steered agent: agent_move -> locomotion (agent mode) -> IK -> FK on the shipped skeleton,
// with the agent's wished velocity scripted (no avoidance or navigation), measured from the FK output.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <memory>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "io/hanim_loader.h"
#include "motion/gait.h"
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
    move = AgentMoveParameters::of(c.motion.style);
    run_or_throw(make_start_walking_job(*c.motion.locomotion, c.motion.paths, t, 0, c.motion.style, true), "start");
    run_or_throw(make_ik_job(c.rig().skeleton, c.motion.locomotion->limbs, t), "ik");
    run_or_throw(make_fk_job(c.rig().skeleton, t), "fk");
  }
  SoaTable& table() { return crowd->world.table(crowd->world.location(walker).table); }
  float agent(std::uint32_t c) { return table().f32(kWalkerAgent, c)[0]; }
  float gait(std::uint32_t c) { return table().f32(kWalkerGait, c)[0]; }

  // One frame with the agent wishing to move at `wish` (m/s, ground x and z); `before_locomotion` may change the
  // walker's columns between agent_move and locomotion (what the last IK run reported, say).
  // `carried`: the velocity avoidance chose, when it is not the wish's (someone in the way).
  void frame(glm::vec2 wish, float dt, const std::function<void(SoaTable&)>& before_locomotion = {},
             std::optional<glm::vec2> carried = std::nullopt) {
    Crowd& c = *crowd;
    SoaTable& t = table();
    // As navigation does: the wish goes through what the body can follow; no one to avoid, so avoidance would
    // return it unchanged.
    const float heading = wish_heading(t.f32(kWalkerAgent, kAgentHeading)[0],
                                       {t.f32(kWalkerAgent, kAgentVx)[0], t.f32(kWalkerAgent, kAgentVz)[0]},
                                       {t.f32(kWalkerAgent, kAgentPrefVx)[0], t.f32(kWalkerAgent, kAgentPrefVz)[0]},
                                       10.0f * wish, move);
    const glm::vec2 pref = followable_velocity(wish, heading,
                                               std::hypot(t.f32(kWalkerAgent, kAgentVx)[0], t.f32(kWalkerAgent, kAgentVz)[0]),
                                               move, dt);
    t.f32(kWalkerAgent, kAgentTargetX)[0] = t.f32(kWalkerAgent, kAgentPx)[0] + 10.0f * wish.x;
    t.f32(kWalkerAgent, kAgentTargetZ)[0] = t.f32(kWalkerAgent, kAgentPz)[0] + 10.0f * wish.y;
    t.f32(kWalkerAgent, kAgentOrcaVx)[0] = t.f32(kWalkerAgent, kAgentPrefVx)[0] = pref.x;
    t.f32(kWalkerAgent, kAgentOrcaVz)[0] = t.f32(kWalkerAgent, kAgentPrefVz)[0] = pref.y;
    if (carried) {
      t.f32(kWalkerAgent, kAgentOrcaVx)[0] = carried->x;
      t.f32(kWalkerAgent, kAgentOrcaVz)[0] = carried->y;
    }
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
  // Stopping, the body changes its pace as a person's does (5.6 m/s^2 at most). Not yet the rest: leaving the
  // idle stance the body goes from still to start_speed in a frame (11 m/s^2 at 60 fps), the 90-degree turn
  // jolts it three times (up to 36 m/s^2), and walking off after turning round comes to 9.8 (docs/crowds.md,
  // "How the bodies move").
  EXPECT_EQ(stop.gait.body_jolts, 0u) << "sharpest change " << stop.gait.body_accel_max_mps2 << " m/s^2";
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

// A rolling stance foot its leg could not reach in the last frame, once the other foot is down
// (GaitStyle::early_lift), lifts into its swing at once, from where it is (the ankle moves no more than a frame's
// swing), and lands at its next heel strike; the same walker told nothing keeps the foot planted until toe-off.
TEST(AgentWalk, ARollingFootOutOfReachLiftsEarly) {
  AgentWalker plain, pushed;
  const LocomotionRig& rig = *plain.crowd->motion.locomotion;
  const float dt = 1.0f / 60.0f;
  const glm::vec2 forward(0.0f, 1.2f);
  const auto leg_value = [](AgentWalker& w, int leg, LegComponent c) {
    return w.gait(kGaitLegs + static_cast<std::uint32_t>(leg) * kLegFloats + c);
  };
  const auto psi_of = [](AgentWalker& w, int leg) {
    const float p = w.gait(kGaitPhase) - 0.5f * static_cast<float>(leg);
    return p - std::floor(p);
  };
  // Walk until a stance leg is in the window: past the other foot's heel strike and early_lift of its stance.
  int leg = -1;
  float sf = 0.0f;
  for (int f = 0; f < 600 && leg < 0; ++f) {
    plain.frame(forward, dt);
    pushed.frame(forward, dt);
    sf = gait_parameters(plain.gait(kGaitHeight), plain.gait(kGaitCadence)).stance_fraction();
    for (int l = 0; l < 2; ++l) {
      const float psi = psi_of(plain, l);
      // Not on the window's first frame: the next frame must still be inside it for the lift to be seen.
      if (f > 120 && leg_value(plain, l, kLegSwinging) < 0.5f && psi > plain.crowd->motion.style.early_lift * sf + 0.01f &&
          psi > 0.52f && psi < sf - 0.03f)
        leg = l;
    }
  }
  ASSERT_GE(leg, 0) << "the walk reached a late stance";
  ASSERT_EQ(plain.gait(kGaitPhase), pushed.gait(kGaitPhase));
  const std::int32_t ankle = rig.limbs[leg == 0 ? kLeftLeg : kRightLeg].lower;
  const glm::vec3 before = pushed.joint(ankle);
  plain.frame(forward, dt);
  pushed.frame(forward, dt, [&](SoaTable& t) {
    t.u32(kWalkerIkFlags, static_cast<std::uint32_t>(leg))[0] = kIkUnreachable;
  });
  EXPECT_LT(leg_value(plain, leg, kLegSwinging), 0.5f) << "told nothing, the foot stays down";
  ASSERT_GT(leg_value(pushed, leg, kLegSwinging), 0.5f) << "out of reach late in stance, the foot lifts";
  const float lifted_at = leg_value(pushed, leg, kLegEarlyLift);
  EXPECT_GT(lifted_at, 0.5f);
  EXPECT_LT(lifted_at, sf);
  EXPECT_LT(glm::length(pushed.joint(ankle) - before), 0.05f) << "it leaves from where it was";
  // It lands at its next heel strike, and the walk goes on without NaN.
  bool landed = false;
  for (int f = 0; f < 120 && !landed; ++f) {
    pushed.frame(forward, dt);
    landed = leg_value(pushed, leg, kLegSwinging) < 0.5f;
    if (landed) {
      EXPECT_LT(psi_of(pushed, leg), 0.1f) << "landed at the heel strike";
    }
    for (std::uint32_t c = 0; c < kAgentFloats; ++c) ASSERT_TRUE(std::isfinite(pushed.agent(c)));
  }
  EXPECT_TRUE(landed);
}

// Where a body faces: its wish, or, carried at a walking pace within face_side_angle of the way to its target,
// where it goes.
// Late in a stance with both feet down, the body carried ahead in one frame: 0.2 m is beyond what IK can hold the
// trailing foot at (its joints' limits), 0.1 m is not. Asked before IK runs (GaitStyle::lift_on_ik_miss), the leg
// lifts in the frame IK could not hold it, and only then; told only by IK's flags, it is still down in that frame,
// where IK's clamp turns the foot about the ankle (in the crowds its toe tip slid 10-35 mm so).
TEST(AgentWalk, AStanceFootIkCannotHoldLiftsInThatFrame) {
  struct Outcome {
    bool lifted = false;
    std::uint32_t flags = 0;  // the leg's IK flags after the frame
  };
  const auto carried = [](bool rule, float push) {
    AgentWalker w;
    w.crowd->motion.style.lift_on_ik_miss = rule;
    const float dt = 1.0f / 60.0f;
    const glm::vec2 forward(0.0f, 1.2f);
    const auto swinging = [&](int l) {
      return w.gait(kGaitLegs + static_cast<std::uint32_t>(l) * kLegFloats + kLegSwinging) > 0.5f;
    };
    int leg = -1;
    for (int f = 0; f < 600 && leg < 0; ++f) {
      w.frame(forward, dt);
      const float sf = gait_parameters(w.gait(kGaitHeight), w.gait(kGaitCadence)).stance_fraction();
      for (int l = 0; l < 2; ++l) {
        float psi = w.gait(kGaitPhase) - 0.5f * static_cast<float>(l);
        psi -= std::floor(psi);
        if (f > 120 && !swinging(l) && !swinging(1 - l) && psi > w.crowd->motion.style.early_lift * sf + 0.01f &&
            psi > 0.52f && psi < sf - 0.03f)
          leg = l;
      }
    }
    EXPECT_GE(leg, 0) << "the walk reached a late stance in double support";
    if (leg < 0) return Outcome{};
    w.frame(forward, dt, [&](SoaTable& t) { t.f32(kWalkerAgent, kAgentPz)[0] += push; });
    for (std::uint32_t c = 0; c < kAgentFloats; ++c) EXPECT_TRUE(std::isfinite(w.agent(c)));
    return Outcome{swinging(leg), w.table().u32(kWalkerIkFlags, static_cast<std::uint32_t>(leg))[0]};
  };
  const Outcome far_told = carried(false, 0.2f), far_asked = carried(true, 0.2f);
  const Outcome near_told = carried(false, 0.1f), near_asked = carried(true, 0.1f);
  EXPECT_NE(far_told.flags & (kIkUnreachable | kIkLimitsInfeasible), 0u) << "IK could not hold the foot";
  EXPECT_FALSE(far_told.lifted) << "told only by IK's flags, the foot is still down in that frame";
  EXPECT_TRUE(far_asked.lifted) << "asked before IK, it lifts in that frame";
  EXPECT_EQ(near_told.flags & (kIkUnreachable | kIkLimitsInfeasible), 0u) << "IK held the foot";
  EXPECT_FALSE(near_told.lifted);
  EXPECT_FALSE(near_asked.lifted) << "a foot IK holds stays down";
}

// A walker carried ahead of its body while on one foot (its agent moved 0.5 m further over ten frames, from the
// frame after the other foot lifted): the stance foot holds the body back (GaitStyle::lag_dip), and the swing,
// aimed where the body was predicted to be, would land beyond the leg's reach ahead of it. Landing within reach
// (GaitStyle::land_within_reach), the body catches up over the next steps instead of being pulled to the foot in
// one frame (measured: its fastest frame after the push 1.42 m/s, without the rule 4.07 m/s).
TEST(AgentWalk, AFootLandsWithinReachOfABodyHeldBehind) {
  struct Outcome {
    double fastest_after = 0.0;  // m/s: the body's fastest frame once the push is over
    double lag_most = 0.0;       // m: how far the stance foot held the body behind its agent
    GaitReport gait;
  };
  constexpr int kPushFrames = 10;
  const auto carried = [](bool rule, float push) {
    AgentWalker w;
    w.crowd->motion.style.land_within_reach = rule;
    GaitMetrics metrics(w.crowd->rig().skeleton, *w.crowd->motion.locomotion, w.crowd->motion.style);
    const float dt = 1.0f / 60.0f;
    const glm::vec2 forward(0.0f, 1.2f);
    const auto swinging = [&](int l) {
      return w.gait(kGaitLegs + static_cast<std::uint32_t>(l) * kLegFloats + kLegSwinging) > 0.5f;
    };
    const auto body = [&] {
      return glm::vec2(w.table().f32(kWalkerPlacement, 0)[0], w.table().f32(kWalkerPlacement, 2)[0]);
    };
    Outcome o;
    bool was_swinging[2] = {swinging(0), swinging(1)};
    int pushed_at = -1;
    glm::vec2 last = body();
    for (int f = 0; f < 360; ++f) {
      // After two seconds, from the frame after a foot lifts: the agent carried `push` further over kPushFrames.
      if (pushed_at < 0 && f > 120 && swinging(0) != swinging(1) &&
          (swinging(0) != was_swinging[0] || swinging(1) != was_swinging[1]))
        pushed_at = f;
      was_swinging[0] = swinging(0), was_swinging[1] = swinging(1);
      const bool pushing = pushed_at >= 0 && f < pushed_at + kPushFrames;
      w.frame(forward, dt, [&](SoaTable& t) {
        if (pushing) t.f32(kWalkerAgent, kAgentPz)[0] += push / static_cast<float>(kPushFrames);
      });
      metrics.observe(walker_lanes(w.table(), w.crowd->joint_count()), w.crowd->motion.paths, dt);
      const glm::vec2 now = body();
      if (pushed_at >= 0 && !pushing) o.fastest_after = std::max<double>(o.fastest_after, glm::length(now - last) / dt);
      o.lag_most = std::max<double>(o.lag_most, std::hypot(w.gait(kGaitLagX), w.gait(kGaitLagZ)));
      last = now;
    }
    EXPECT_GE(pushed_at, 0);
    o.gait = metrics.report();
    return o;
  };
  const Outcome pulled = carried(false, 0.5f), within = carried(true, 0.5f);
  for (const Outcome* o : {&pulled, &within})
    std::printf("%s: held %.3f m behind, fastest body after the push %.2f m/s, foot slide %.2f mm\n",
                o == &pulled ? "pulled to the foot" : "landing within reach", o->lag_most, o->fastest_after,
                o->gait.foot_slide_mm_max);
  EXPECT_GT(pulled.lag_most, 0.15) << "the stance foot held the body back";
  EXPECT_GT(within.lag_most, 0.15);
  EXPECT_GT(pulled.fastest_after, 3.5) << "without the rule the landing foot pulls the body to it";
  EXPECT_LT(within.fastest_after, 2.0) << "the body catches up at a walk";
  EXPECT_LT(within.gait.foot_slide_mm_max, 1.0);
  EXPECT_EQ(within.gait.nan_count, 0u);
}

TEST(AgentWalk, FacingDirectionIsTheWishUnlessCarriedAcrossAtWalkingPace) {
  const float speed = 0.6f, side = 1.4f;
  const glm::vec2 wish(0.0f, 1.2f), ahead(0.0f, 10.0f);
  EXPECT_EQ(facing_direction({1.0f, 0.2f}, wish, ahead, speed, side), glm::vec2(1.0f, 0.2f)) << "79 deg off, 1 m/s";
  EXPECT_EQ(facing_direction({0.3f, 0.1f}, wish, ahead, speed, side), wish) << "too slow to turn the body";
  EXPECT_EQ(facing_direction({0.5f, -0.9f}, wish, ahead, speed, side), wish) << "carried backwards: it steps back";
  // The wish turned along a flow the body faced, the target behind it: carried along, it faces its wish, which turns
  // back towards the target at the turn rate (followable_velocity), not where it goes.
  EXPECT_EQ(facing_direction({1.0f, 0.0f}, {0.15f, 0.02f}, {-5.0f, -5.0f}, speed, side), glm::vec2(0.15f, 0.02f));
  EXPECT_EQ(facing_direction({1.0f, 0.2f}, wish, glm::vec2(0.0f), speed, side), glm::vec2(1.0f, 0.2f))
      << "no target: the wish's way";
  EXPECT_EQ(facing_direction({0.7f, 0.0f}, {0.0f, 0.01f}, ahead, speed, side), glm::vec2(0.7f, 0.0f)) << "no wish";
  EXPECT_EQ(facing_direction({0.01f, 0.0f}, {0.0f, 0.01f}, ahead, speed, side), glm::vec2(0.0f)) << "nothing either way";
  // The walk's own angle: swept nearly across its way (the other stream of a crossing) a body keeps facing its way,
  // so its wish stays along it; carried 60 degrees off it turns into the gap.
  const GaitStyle style;
  EXPECT_EQ(facing_direction({1.2f, 0.1f}, wish, ahead, style.face_velocity_speed, style.face_side_angle), wish)
      << "85 deg off at 1.2 m/s";
  EXPECT_EQ(facing_direction({1.0f, 0.58f}, wish, ahead, style.face_velocity_speed, style.face_side_angle),
            glm::vec2(1.0f, 0.58f))
      << "60 deg off";
}

// Edging round a tight circle, a stance foot under a body that has turned past what the legs twist lifts early (once
// the other foot is down) rather than being yawed on its ball by IK's orientation clamp.
TEST(AgentWalk, AStanceFootTwistedPastTheLegsLiftsEarly) {
  double slide[2] = {0.0, 0.0};
  std::size_t clamped[2] = {0, 0};
  for (int rule = 0; rule < 2; ++rule) {
    AgentWalker w;
    if (rule == 0) {
      w.crowd->motion.style.lift_twist = 10.0f;  // off, and so is the lift in the frame IK cannot hold the foot,
      w.crowd->motion.style.lift_on_ik_miss = false;  // which lifts such a foot too (in the frame the clamp binds)
    }
    GaitMetrics metrics(w.crowd->rig().skeleton, *w.crowd->motion.locomotion, w.crowd->motion.style);
    const float dt = 1.0f / 60.0f;
    for (int f = 0; f < 900; ++f) {
      // Edging along at 0.3 m/s (its cadence at the agents' floor, 80 steps a minute: long stances) on a tight
      // circle, its wish turning at 1.2 rad/s.
      const float angle = f < 60 ? 0.0f : 1.2f * static_cast<float>(f - 60) * dt;
      const glm::vec2 wish = 0.3f * glm::vec2(std::sin(angle), std::cos(angle));
      w.frame(wish, dt);
      metrics.observe(walker_lanes(w.table(), w.crowd->joint_count()), w.crowd->motion.paths, dt);
      for (std::uint32_t c = 0; c < kAgentFloats; ++c) ASSERT_TRUE(std::isfinite(w.agent(c)));
    }
    slide[rule] = metrics.report().foot_slide_mm_max;
    clamped[rule] = static_cast<std::size_t>(metrics.report().ik_orientation_clamped);
  }
  std::printf("tight circle: foot slide %.2f mm without the twist lift, %.2f mm with; orientation clamps %zu / %zu\n",
              slide[0], slide[1], clamped[0], clamped[1]);
  EXPECT_LT(slide[1], 1.0);
  EXPECT_LT(clamped[1], clamped[0]);
  EXPECT_GT(slide[0], 1.0) << "without the lift the twisted foot is yawed on its ball";
}

// On one foot a body turns no further over it than stance_twist: the turn that would twist the foot further is cut
// to the limit, one that untwists it is whole, and a foot already past the limit is not twisted more.
TEST(AgentWalk, ABodyOnOneFootTurnsOnlyAsFarAsTheLegTwists) {
  const float limit = 0.85f;
  EXPECT_FLOAT_EQ(stance_limited_turn(0.5f, 0.1f, 0.0f, limit), 0.1f) << "within the limit";
  EXPECT_NEAR(stance_limited_turn(0.8f, 0.1f, 0.0f, limit), 0.05f, 1e-6f) << "cut at the limit";
  EXPECT_NEAR(stance_limited_turn(-0.8f, -0.1f, 0.0f, limit), -0.05f, 1e-6f) << "either way";
  EXPECT_FLOAT_EQ(stance_limited_turn(0.9f, 0.05f, 0.0f, limit), 0.0f) << "already past: held";
  EXPECT_FLOAT_EQ(stance_limited_turn(0.9f, -0.05f, 0.0f, limit), -0.05f) << "untwisting is whole";
  // Headings wrap: a foot planted at 3.0 rad under a body at -3.0 is twisted 0.28 rad, not 6.0.
  EXPECT_FLOAT_EQ(stance_limited_turn(-3.0f, 0.1f, 3.0f, limit), 0.1f);
  EXPECT_NEAR(stance_limited_turn(-3.0f, 0.7f, 3.0f, limit), limit - (6.2831853f - 6.0f), 1e-5f);

  // Edging along at 0.3 m/s (the agents' cadence floor: stances of ~0.9 s) with a wish that keeps turning at
  // 1.6 rad/s, faster than the footprints' predictions assume: over a foot in single support the body's twist
  // stays within the limit, and without the rule it went past what the legs twist.
  // Runs: the rule off (the early lift of a twisted foot on, which cannot act on one foot); the rule alone; both
  // (the default: a foot held at the limit lifts in the double support that follows).
  float worst[3] = {0.0f, 0.0f, 0.0f};
  double slide[3] = {0.0, 0.0, 0.0};
  for (int rule = 0; rule < 3; ++rule) {
    AgentWalker w;
    if (rule == 0) w.crowd->motion.style.stance_twist = 10.0f;  // off
    if (rule == 1) w.crowd->motion.style.lift_twist = 10.0f;
    w.move = AgentMoveParameters::of(w.crowd->motion.style);
    GaitMetrics metrics(w.crowd->rig().skeleton, *w.crowd->motion.locomotion, w.crowd->motion.style);
    const float dt = 1.0f / 60.0f;
    for (int f = 0; f < 900; ++f) {
      const float angle = f < 60 ? 0.0f : 1.6f * static_cast<float>(f - 60) * dt;
      w.frame(0.3f * glm::vec2(std::sin(angle), std::cos(angle)), dt);
      metrics.observe(walker_lanes(w.table(), w.crowd->joint_count()), w.crowd->motion.paths, dt);
      for (int leg = 0; leg < 2; ++leg) {
        const auto c = [&](int l, std::uint32_t k) { return w.gait(kGaitLegs + static_cast<std::uint32_t>(l) * kLegFloats + k); };
        if (c(leg, kLegSwinging) < 0.5f && c(1 - leg, kLegSwinging) > 0.5f)
          worst[rule] = std::max(worst[rule], std::abs(wrap_angle(w.agent(kAgentHeading) - c(leg, kLegPlantHeading))));
      }
      for (std::uint32_t c = 0; c < kAgentFloats; ++c) ASSERT_TRUE(std::isfinite(w.agent(c)));
    }
    slide[rule] = metrics.report().foot_slide_mm_max;
  }
  std::printf("wish turning at 1.6 rad/s: twist on one foot %.2f rad without the rule, %.2f with it alone, %.2f with "
              "the early lift too; foot slide %.2f / %.2f / %.2f mm\n", worst[0], worst[1], worst[2], slide[0],
              slide[1], slide[2]);
  EXPECT_GT(worst[0], 0.9f) << "without it the body turns on past the legs' twist";
  EXPECT_GT(slide[0], 1.0) << "and IK's clamp yaws the foot";
  EXPECT_LE(worst[1], limit + 1e-4f);
  EXPECT_LE(worst[2], limit + 1e-4f);
  EXPECT_LT(slide[1], slide[0]);
  EXPECT_LT(slide[2], 1.0);
}

// A walker settling into (or leaving) its idle stance stands with its feet side by side and flat: its body does not
// turn towards a wish too slow to walk, which twisted the legs over the planted feet (past max_foot_twist a flat
// foot cannot pivot) and slid the toes by up to 3 cm in the crossing.
TEST(AgentWalk, ABodySettlingIntoItsStanceDoesNotTurnOverItsFeet) {
  AgentWalker w;
  GaitMetrics metrics(w.crowd->rig().skeleton, *w.crowd->motion.locomotion, w.crowd->motion.style);
  const float dt = 1.0f / 60.0f;
  std::optional<float> settling_heading;
  for (int f = 0; f < 420; ++f) {
    // Walking +Z, then wishing for 6 cm/s towards +X: slower than stand_speed, so it brakes (turning a little on
    // the way) and stands.
    w.frame(f < 120 ? glm::vec2(0.0f, 1.2f) : glm::vec2(0.06f, 0.0f), dt);
    metrics.observe(walker_lanes(w.table(), w.crowd->joint_count()), w.crowd->motion.paths, dt);
    if (f >= 120 && w.gait(kGaitIdle) > 0.0f && !settling_heading) settling_heading = w.agent(kAgentHeading);
  }
  ASSERT_TRUE(settling_heading.has_value());
  EXPECT_LT(std::abs(*settling_heading), 1.0f) << "it began to settle before turning to +X";
  EXPECT_EQ(w.agent(kAgentHeading), *settling_heading) << "standing, it did not turn";
  EXPECT_FLOAT_EQ(w.gait(kGaitIdle), 1.0f) << "standing";
  EXPECT_LT(metrics.report().foot_slide_mm_max, 1.0);
}

// Swept further off its way than face_side_angle, a body keeps facing nearly its wish but turns towards the line
// it is carried along until it goes across itself at no more than face_side_speed: a forward gait steps sideways
// that fast and no faster. Carried backwards at a slant it turns towards straight back.
TEST(AgentWalk, FacingTurnsOffTheWishOnlyAsFarAsASideStepNeeds) {
  const float speed = 0.6f, side = 1.2f, side_speed = 0.4f;
  const glm::vec2 wish(0.0f, 1.2f), ahead(0.0f, 10.0f);
  const auto across = [](glm::vec2 facing, glm::vec2 v) {
    const glm::vec2 f = glm::normalize(facing);
    return f.y * v.x - f.x * v.y;
  };
  const auto along = [](glm::vec2 facing, glm::vec2 v) { return glm::dot(glm::normalize(facing), v); };
  const glm::vec2 swept(1.2f, 0.1f);  // 85 degrees off at 1.2 m/s: beyond `side`, so not faced
  const glm::vec2 f = facing_direction(swept, wish, ahead, speed, side, side_speed);
  EXPECT_NEAR(across(f, swept), side_speed, 1e-4f);
  EXPECT_GT(along(f, swept), 0.0f) << "the carry stays ahead of the body";
  EXPECT_GT(f.x, 0.0f) << "turned towards the carry";
  EXPECT_NEAR(glm::length(f), glm::length(wish), 1e-4f);
  const glm::vec2 mirrored = facing_direction({-1.2f, 0.1f}, wish, ahead, speed, side, side_speed);
  EXPECT_NEAR(mirrored.x, -f.x, 1e-4f);
  EXPECT_NEAR(mirrored.y, f.y, 1e-4f);
  const glm::vec2 back_slant(0.8f, -0.9f);  // backwards and 0.8 m/s across
  const glm::vec2 b = facing_direction(back_slant, wish, ahead, speed, side, side_speed);
  EXPECT_NEAR(std::abs(across(b, back_slant)), side_speed, 1e-4f);
  EXPECT_LT(along(b, back_slant), 0.0f) << "still stepping back, not turned round";
  EXPECT_LT(b.x, 0.0f) << "turned so the carry comes nearer straight behind";
  EXPECT_EQ(facing_direction({0.35f, 0.2f}, wish, ahead, speed, side, side_speed), wish) << "0.35 m/s across, slow";
  EXPECT_EQ(facing_direction(swept, wish, ahead, speed, side, 0.0f), wish) << "the rule off";
  // Navigation turns the wish from the heading less this turn: a body turned for its feet still wishes for its way.
  AgentMoveParameters p;
  p.face_velocity_speed = speed, p.face_side_angle = side, p.face_side_speed = side_speed;
  const float turned = std::atan2(f.x, f.y);
  EXPECT_NEAR(wish_heading(turned, swept, wish, ahead, p), 0.0f, 1e-4f);
  EXPECT_EQ(wish_heading(0.3f, {1.0f, 0.58f}, wish, ahead, p), 0.3f) << "facing its velocity, as chosen";
}

// Swept nearly across its way at 1.2 m/s (another stream of a crossing), beyond face_side_angle: the walker turns only
// as far as its feet need, and once turned keeps them planted and goes on wishing for its way; kept facing its wish
// it walks sideways at 1.2 m/s on a forward gait and a foot drags every stance.
TEST(AgentWalk, ABodySweptAcrossItsWayTurnsAsFarAsItsFeetNeedAndKeepsItsWish) {
  const glm::vec2 wish(0.0f, 1.2f), swept(1.19f, 0.1f);
  double slide[2] = {0.0, 0.0};
  float heading_after[2] = {0.0f, 0.0f}, wish_after[2] = {0.0f, 0.0f};
  for (int rule = 0; rule < 2; ++rule) {
    AgentWalker w;
    if (rule == 0) {
      w.crowd->motion.style.face_side_speed = 0.0f;
      w.move = AgentMoveParameters::of(w.crowd->motion.style);
    }
    GaitMetrics metrics(w.crowd->rig().skeleton, *w.crowd->motion.locomotion, w.crowd->motion.style);
    const float dt = 1.0f / 60.0f;
    for (int f = 0; f < 420; ++f) {
      w.frame(wish, dt, {}, f < 90 ? std::nullopt : std::optional<glm::vec2>(swept));
      // From 2.5 s into the sweep: the turn itself (about a second at the turn rate while carried at 1.2 m/s) still
      // strains the feet for a few stances (up to 12 mm here).
      if (f >= 240) metrics.observe(walker_lanes(w.table(), w.crowd->joint_count()), w.crowd->motion.paths, dt);
      for (std::uint32_t c = 0; c < kAgentFloats; ++c) ASSERT_TRUE(std::isfinite(w.agent(c)));
    }
    slide[rule] = metrics.report().foot_slide_mm_max;
    heading_after[rule] = w.agent(kAgentHeading);
    wish_after[rule] = std::atan2(w.agent(kAgentPrefVx), w.agent(kAgentPrefVz));
  }
  std::printf("swept across: foot slide %.2f mm facing its wish, %.2f mm turned for its feet; heading %.2f / %.2f rad, "
              "wish %.2f / %.2f rad\n",
              slide[0], slide[1], heading_after[0], heading_after[1], wish_after[0], wish_after[1]);
  const GaitStyle style;
  const float side_speed = std::sin(std::atan2(swept.x, swept.y) - heading_after[1]) * glm::length(swept);
  EXPECT_NEAR(side_speed, style.face_side_speed, 0.02f) << "turned as far as its feet need";
  EXPECT_NEAR(heading_after[0], 0.0f, 0.05f) << "without the rule it keeps facing its wish";
  EXPECT_NEAR(wish_after[1], 0.0f, 0.05f) << "still wishing for its way";
  EXPECT_LT(slide[1], 1.0);
  EXPECT_GT(slide[0], 3.0 * slide[1] + 1.0) << "the rule is what keeps the feet";
}

// Carried across its wish at a walking pace for a few seconds (avoidance sending it round someone), a walker turns
// to face where it goes and keeps its feet planted; told to keep facing its wish, the same walker walks sideways on a
// forward gait.
TEST(AgentWalk, ACarriedBodyTurnsToWhereItGoesAndKeepsItsFeet) {
  const glm::vec2 wish(0.0f, 1.2f), carried(0.99f, 0.57f);  // 1.14 m/s, 60 deg off its wish
  double slide[2] = {0.0, 0.0};
  float heading_after[2] = {0.0f, 0.0f};
  for (int facing = 0; facing < 2; ++facing) {
    AgentWalker w;
    if (facing == 0) {
      w.crowd->motion.style.face_velocity_speed = 1e6f;
      w.crowd->motion.style.face_side_speed = 0.0f;
      w.move = AgentMoveParameters::of(w.crowd->motion.style);
    }
    GaitMetrics metrics(w.crowd->rig().skeleton, *w.crowd->motion.locomotion, w.crowd->motion.style);
    const float dt = 1.0f / 60.0f;
    for (int f = 0; f < 240; ++f) {
      w.frame(f < 90 ? wish : wish, dt, {}, f < 90 ? std::nullopt : std::optional<glm::vec2>(carried));
      metrics.observe(walker_lanes(w.table(), w.crowd->joint_count()), w.crowd->motion.paths, dt);
      for (std::uint32_t c = 0; c < kAgentFloats; ++c) ASSERT_TRUE(std::isfinite(w.agent(c)));
    }
    slide[facing] = metrics.report().foot_slide_mm_max;
    heading_after[facing] = w.agent(kAgentHeading);
  }
  std::printf("carried across: foot slide %.2f mm facing its wish, %.2f mm turned; heading %.2f / %.2f rad\n",
              slide[0], slide[1], heading_after[0], heading_after[1]);
  EXPECT_NEAR(heading_after[1], std::atan2(carried.x, carried.y), 0.05f) << "turned to where it goes";
  EXPECT_NEAR(heading_after[0], 0.0f, 0.05f) << "told to, it keeps facing its wish";
  EXPECT_LT(slide[1], 1.0);
}

// Carried backwards (someone walking into it), a walker keeps facing its wish and steps back; the foot it had planted
// ahead stays down, its heel neither raised by the stance's schedule past what the ankle allows under a shin
// leaning back nor left to drag.
TEST(AgentWalk, ACarriedBackBodyStepsBackWithItsFeetDown) {
  for (const float back : {0.3f, 0.6f}) {
    AgentWalker w;
    GaitMetrics metrics(w.crowd->rig().skeleton, *w.crowd->motion.locomotion, w.crowd->motion.style);
    const float dt = 1.0f / 60.0f;
    const glm::vec2 wish(0.0f, 1.2f);
    for (int f = 0; f < 300; ++f) {
      w.frame(wish, dt, {}, f < 120 ? std::nullopt : std::optional<glm::vec2>(glm::vec2(0.0f, -back)));
      metrics.observe(walker_lanes(w.table(), w.crowd->joint_count()), w.crowd->motion.paths, dt);
      for (std::uint32_t c = 0; c < kAgentFloats; ++c) ASSERT_TRUE(std::isfinite(w.agent(c)));
    }
    const GaitReport r = metrics.report();
    std::printf("carried back at %.1f m/s: foot slide %.2f mm, orientation clamps %zu\n", back, r.foot_slide_mm_max,
                static_cast<std::size_t>(r.ik_orientation_clamped));
    EXPECT_NEAR(w.agent(kAgentHeading), 0.0f, 0.05f) << "it keeps facing its wish";
    EXPECT_LT(w.agent(kAgentPz), 1.6f) << "it went back";
    EXPECT_LT(r.foot_slide_mm_max, 1.0);
  }
}

// The body's own motion is measured too: a walk's pelvis keeps its speed give or take its sway, and a body moved
// 10 cm off its walk for one frame (its placement shifted after FK, as a yank to an unreachable foot would) is
// counted as a jolt, both ways, with the speed it showed.
TEST(AgentWalk, GaitMetricsCountABodyJerkedOffItsWalk) {
  AgentWalker w;
  const LocomotionRig& rig = *w.crowd->motion.locomotion;
  float clock = 0.0f;
  constexpr float dt = 1.0f / 60.0f;
  GaitMetrics start(w.crowd->rig().skeleton, rig, w.crowd->motion.style);
  walk(w, 3.0f, [](float) { return glm::vec2(0.0f, 1.3f); }, start, clock, dt);
  GaitMetrics smooth(w.crowd->rig().skeleton, rig, w.crowd->motion.style);
  const GaitReport walking = walk(w, 2.0f, [](float) { return glm::vec2(0.0f, 1.3f); }, smooth, clock, dt).gait;
  EXPECT_EQ(walking.body_jolts, 0u);
  EXPECT_LT(walking.body_accel_max_mps2, kBodyJoltAccel / 2.0);
  EXPECT_GT(walking.body_speed_max_mps, 1.2);
  EXPECT_LT(walking.body_speed_max_mps, 1.6);

  GaitMetrics jerked(w.crowd->rig().skeleton, rig, w.crowd->motion.style);
  for (int f = 0; f < 60; ++f) {
    w.frame({0.0f, 1.3f}, dt);
    if (f == 30) w.table().f32(kWalkerPlacement, 0)[0] += 0.1f;  // x, this frame only: locomotion rewrites it
    jerked.observe(walker_lanes(w.table(), w.crowd->joint_count()), w.crowd->motion.paths, dt);
  }
  const GaitReport r = jerked.report();
  EXPECT_GE(r.body_jolts, 2u) << "off and back";
  EXPECT_GT(r.body_speed_max_mps, 0.1 / dt * 0.9);
  EXPECT_GT(r.body_accel_max_mps2, kBodyJoltAccel);
}

TEST(AgentWalk, AgentMoveRefusesNonFiniteVelocities) {
  AgentWalker w;
  SoaTable& t = w.table();
  t.f32(kWalkerAgent, kAgentOrcaVx)[0] = std::nanf("");
  const float before = w.agent(kAgentPx);
  EXPECT_FALSE(make_agent_move_job(t, 1.0f / 60.0f, w.move).run());
  EXPECT_EQ(w.agent(kAgentPx), before);
}

TEST(AgentWalk, AgentMoveRefusesABadStanceTwist) {
  AgentWalker w;
  SoaTable& t = w.table();
  const float before = w.agent(kAgentPx);
  for (const float limit : {std::nanf(""), -0.1f}) {
    AgentMoveParameters p = w.move;
    p.stance_twist = limit;
    EXPECT_FALSE(make_agent_move_job(t, 1.0f / 60.0f, p).run()) << limit;
    EXPECT_EQ(w.agent(kAgentPx), before);
  }
  AgentMoveParameters off = w.move;
  off.stance_twist = 10.0f;  // off, as the tests above use it
  EXPECT_TRUE(make_agent_move_job(t, 1.0f / 60.0f, off).run());
}

}  // namespace
}  // namespace strata
