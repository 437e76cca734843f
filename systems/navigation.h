#pragma once
// Navigation: what each agent of a scenario crowd wants to do, before avoidance says what it may. Two jobs:
//
// SteerJob (every agent, every step, in parallel): arrival at the goal (within its radius) and the next goal for
// waypoint cycles and random goals; advancing past path corners as they are reached; the preferred velocity,
// towards the first corner at the agent's preferred speed, easing to a stop at a final goal, as far as the body can
// follow this step (agent_move.h followable_velocity: turning, acceleration); and the flag asking
// for a new path (a new goal, no corners left, or the periodic replan is due).
//
// PlanJob (the agents the frame script picked this step, serially, with one Detour query): a path on the
// navigation mesh (nav/navmesh.h) from the agent to its goal, kept as its first kAgentCorners corners. The frame
// script staggers replans: a few agents a step, those with no path first, the rest every replan_period seconds
// in turn, so no step plans everyone (the stall crowd users report when every agent replans on one frame).
//
// Agent columns: components/walker.h (AgentComponent, AgentIntComponent, kWalkerAgentCorners).
//   SteerJob reads:  agent (position, velocity, goal, radius, preferred speed, replan timer), state, corners,
//                    the groups' goals, the ground, dt
//            writes: agent (preferred velocity, goal, steering target, replan timer, travel time and best
//                    distance on a new goal), state (flags, waypoint, random state), corners (advanced)
//   PlanJob  reads:  agent (position, goal), the navigation mesh
//            writes: corners, agent (goal snapped onto the mesh when it lies off it), state (flags)
#include <cstdint>
#include <span>

#include <glm/vec2.hpp>

#include "components/scenario.h"
#include "components/walker.h"
#include "ecs/column_view.h"
#include "systems/agent_move.h"

namespace strata {

class NavQuery;

struct SteeringParameters {
  float corner_reached = 0.5f;  // m: a corner this near is passed (the next one steered at)
  float slow_radius = 1.5f;     // m: an agent eases its speed down over this distance before a final goal
  float replan_period = 3.0f;   // s between an agent's replans
  float wobble = 0.1f;          // rad: seeded jitter of the wished direction, to break symmetric standoffs
  float settle_after = 2.0f;    // s without headway after reaching a final goal: it stands where it is
  // A region goal: an agent settles (as above) only this far inside the region; nearer its edge it takes another
  // point of the region instead, so those who have just come in move on and do not wall the entrance off.
  float settle_depth = 2.0f;    // m
  // A region goal's points (the first and those drawn again outside it) keep this far from the edge the agent
  // comes in by (region_point_past_entrance). Measured over 7 seeds each, before making way (bottleneck: mean share
  // in after 240 s; crossing: runs with every agent in): 0 m 91.8 % / 7 of 7, 1 m 97.2 % / 7 (98.9 % in a first
  // form that rescaled the draw the other way round), 1.5 m (that first form) 98.4 % / 7, 2 m (crossing only) 3 of
  // 7: a crossing agent carried by the other group's stream into that group's denser region stays there.
  float entrance_margin = 1.0f; // m
  // An agent standing at its final goal whose avoidance answer is a direction to make way (AvoidanceParameters::
  // make_way; at least half a unit long) moves its standing spot this far that way, walks there and stands again.
  // 0: it stands where it is, whoever presses.
  float make_way_step = 0.8f;   // m
};

struct SteerJob {
  ColumnView<float> agent;                 // kAgentFloats
  ColumnView<std::uint32_t> state;         // kAgentInts
  ColumnView<float> corners;               // kAgentCorners * 2 + 1
  std::span<const ScenarioGoal> goals;     // per group (kAgentGroup indexes it)
  glm::vec2 ground_min{0.0f}, ground_max{0.0f};  // random goals are drawn inside, 1 m in from the edge
  SteeringParameters params;
  AgentMoveParameters body;  // what a walking body can follow (systems/agent_move.h followable_velocity)
  float dt = 0.0f;

  bool validate() const;
  bool run() const;
};

struct PlanJob {
  NavQuery* query = nullptr;
  ColumnView<float> agent;
  ColumnView<std::uint32_t> state;
  ColumnView<float> corners;
  std::span<const std::uint32_t> rows;  // rows to plan, in this order
  std::span<const ScenarioGoal> goals;
  glm::vec2 ground_min{0.0f}, ground_max{0.0f};  // random goals that fall on an obstacle are drawn again here
  float replan_period = 3.0f;

  bool validate() const;
  bool run() const;
};

SteerJob make_steer_job(SoaTable& walkers, std::span<const ScenarioGoal> goals, glm::vec2 ground_min,
                        glm::vec2 ground_max, const SteeringParameters& params, const AgentMoveParameters& body,
                        float dt);
PlanJob make_plan_job(SoaTable& walkers, NavQuery& query, std::span<const std::uint32_t> rows,
                      std::span<const ScenarioGoal> goals, glm::vec2 ground_min, glm::vec2 ground_max,
                      float replan_period);

// Whether agent row i wants a path this step (no path yet, or its replan is due): the frame script's candidates.
inline bool agent_wants_plan(const ColumnView<const float>& agent, const ColumnView<const std::uint32_t>& state,
                             std::size_t i) {
  return (state.at(kAgentFlags, i) & kAgentNeedsPath) != 0u || agent.at(kAgentReplanIn, i) <= 0.0f;
}

// The i-th goal of a fresh agent of `goal` spawned at `spawn` (Opposite mirrors it, Region and Random draw with
// `rng`, Waypoints starts at the nearest point). Advances `rng` (xorshift32, never 0).
// A Region's point keeps `entrance_margin` from the edge the agent comes in by (region_point_past_entrance).
glm::vec2 first_goal(const ScenarioGoal& goal, glm::vec2 spawn, glm::vec2 ground_min, glm::vec2 ground_max,
                     std::uint32_t& rng, std::uint32_t& waypoint, float entrance_margin = 0.0f);

// A point of a region goal drawn uniformly (`drawn`) moved off the region's entrance band: along the region's axis
// nearest the way from `from` to the region's centre, the drawn coordinate is rescaled from the region's extent to
// the extent less `entrance_margin` on the side `from` comes in by (unchanged where the region is less than twice
// the margin deep, or for other goal kinds). Without it the first agents in stood anywhere, some at the very edge
// they came in by, and the last ones pressed against a wall of standing bodies: the bottleneck after 200 s had its
// room empty and 15 % of its agents outside the region's near edge.
glm::vec2 region_point_past_entrance(const ScenarioGoal& goal, glm::vec2 drawn, glm::vec2 from, float entrance_margin);

}  // namespace strata
