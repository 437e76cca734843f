#pragma once
// Scenario crowds: walkers that are steered agents (components/scenario.h). What a crowd keeps for them — the
// scenario, its navigation mesh and one Detour query, its obstacles for avoidance, the parameters and scratch of
// the agent systems — and the frame's agents stage, which runs them in a fixed order before locomotion:
//
//   steer      systems/navigation.h   goals, corners -> preferred velocity, new goals, plan requests  per table
//   plan       systems/navigation.h   a few agents' paths on the navigation mesh (staggered)          budgeted
//   avoidance  systems/avoidance.h    every agent at once, in entity order -> collision-free velocity  gathered
//   move       systems/agent_move.h   velocity turned and limited, position integrated                per table
//
// Avoidance sees every agent whatever table its walker sits in (meshes, impostors, culled): the stage gathers the
// agents' columns into arrays ordered by entity index, so the result depends on the seed and never on tables or
// threads, and scatters the velocities back. A crowd spread over processes (dist/) steers only the agents this
// process holds; `CrowdAgents::exchange` brings in the others near them for avoidance (ghosts) and shares the
// planning budget, so each agent's answer is the one a single process gives.
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "components/scenario.h"
#include "nav/navmesh.h"
#include "systems/agent_move.h"
#include "systems/avoidance.h"
#include "systems/navigation.h"

namespace strata {

struct Crowd;
struct FrameProfile;
class Profiler;

// One agent as the avoidance stage reads it, for crowds whose agents are steered by several processes (dist/).
struct AgentSnapshot {
  std::uint32_t walker = 0;  // entity index: the avoidance order
  float px = 0, pz = 0, vx = 0, vz = 0, pref_vx = 0, pref_vz = 0;
  float radius = 0;     // the disc avoidance keeps clear: the agent's radius plus CrowdAgents::radius_margin
  float max_speed = 0;  // the fastest avoidance may send it
  // Its tether (AvoidanceJob::tether_dx): the walking body's offset from the agent, and how far off it the agent
  // may go (<= 0: none).
  float tether_dx = 0, tether_dz = 0, tether_reach = 0;
  // 1 when it will not move this step (AvoidanceJob::holds: a walker leaving or settling into its stance), else 0.
  float holds = 0;
};
// A plan request competing for the step's planning budget: the most urgent first, ties by entity index.
struct PlanCandidate {
  float urgency = 0;  // seconds overdue; a missing path counts as very overdue
  std::uint32_t walker = 0, table = 0, row = 0;
};
inline bool more_urgent(const PlanCandidate& x, const PlanCandidate& y) {
  return x.urgency != y.urgency ? x.urgency > y.urgency : x.walker < y.walker;
}

// What a crowd spread over several processes plugs into the agents' stages (apps/crowd_distributed.h): each
// process steers only the agents it owns, and two decisions need the others'. Null for a crowd in one process.
class AgentExchange {
 public:
  virtual ~AgentExchange() = default;
  // Avoidance: `mine` are this process's agents after this step's steering (by entity index); `ghosts` receives,
  // in any order, every other process's agent that can touch the answer of one of mine (within two neighbour
  // distances: a neighbour's first-pass velocity enters the second pass).
  virtual void exchange_ghosts(std::span<const AgentSnapshot> mine, std::vector<AgentSnapshot>& ghosts) = 0;
  // Planning: `mine` holds this process's `take` most urgent candidates (more_urgent order); on return, those of
  // them that are among the whole crowd's `take` most urgent, so the budget picks what one process would.
  virtual void select_plans(std::vector<PlanCandidate>& mine, std::size_t take) = 0;
};

struct CrowdAgents {
  Scenario scenario;
  std::vector<ScenarioGoal> goals;  // per spawn group
  std::shared_ptr<const NavMesh> navmesh;
  std::unique_ptr<NavQuery> query;
  std::unique_ptr<ObstacleSet> obstacles;
  // The one ahead on a shared way keeps going, the one behind yields (AvoidanceParameters::right_of_way): over
  // seven bottleneck runs 87 -> 92 % in the goal region after 240 s on average, every crossing agent in with fewer
  // waiting; the plaza's random goals, ~8 more agents stuck. Those standing make way for a walker blocked against
  // them (AvoidanceParameters::make_way, with SteeringParameters::make_way_step): the same seven runs 97 -> 100 %.
  // Agents meeting head-on keep to their right (AvoidanceParameters::passing_angle): the 1,000-agent circle's jam
  // 541 -> 133 agents stuck, the other scenarios within their run-to-run spread (docs/crowds.md). The one ahead
  // backing into the one behind loses its right of way (right_of_way_back_fade): with 0.25 m bodies a push at the
  // bottleneck's door otherwise ran back along a file of agents into the room's corner (a pair overlapping in 2 of
  // 12 seeds; none with the fade).
  // A walker backing off against its wish is counted on for no more than 0.5 m/s of it (back_off_limit): pinned
  // against a wall by one coming the other way it was moved back at up to 1.7 m/s, its feet dragging.
  AvoidanceParameters avoidance{.right_of_way = 0.49f,
                                .right_of_way_back_fade = 0.2f,
                                .make_way = true,
                                .passing_angle = 0.3f,
                                .back_off_limit = 0.5f};
  SteeringParameters steering;
  AgentMoveParameters move;
  // Avoidance keeps discs this much wider than the bodies. 6 cm packed dense crowds so tight that far more of them
  // stalled (crossing: 31 % through in 90 s against 55 % with 2 cm). A walker leaving or settling into its idle
  // stance is held still (agent_move.h) and avoidance is told so (AvoidanceJob::holds): its neighbours avoid it
  // wholly. Before, the margin alone absorbed those holds, and pairs pressed past it in some runs (3 in the
  // crossing at 240 agents with the wish steered from its last direction).
  float radius_margin = 0.02f;
  // Avoidance keeps each agent within this share of kBodyLagMax (systems/locomotion.h, at the walker's scale) of
  // its body, which planted feet may hold back, whenever its half-planes leave a velocity that does (AvoidanceJob::
  // tether_dx): an agent running on ahead, as a jam's sidesteps carried them, left the body stretching for it and
  // its feet dragging (issue 16). Below 1 to leave the body's own bound room (the tether is kept to first order
  // within a step; avoidance.cpp tether_plane); 0.5 let 8 pairs overlap in one crossing run (docs/crowds.md).
  float tether_share = 0.75f;
  std::uint32_t plans_per_step = 24;  // most paths planned in one step (those without a path first)
  double navigation_build_ms = 0;     // building (or loading) the navigation mesh

  // Scratch of the avoidance gather, by entity order; grown, never shrunk.
  AvoidanceScratch scratch;
  std::vector<float> px, pz, vx, vz, pref_vx, pref_vz, radius, max_speed, new_vx, new_vz, tether_dx, tether_dz,
      tether_reach;
  std::vector<std::uint8_t> holds;
  struct Row {
    std::uint32_t walker;  // entity index: the gather's order
    std::uint32_t table, row;
  };
  std::vector<Row> rows;
  std::vector<std::uint32_t> order;  // per avoidance input: its index in `rows`, or ~0u for another process's
  std::vector<PlanCandidate> candidates;
  std::shared_ptr<AgentExchange> exchange;  // set when the crowd is spread over processes
  std::vector<AgentSnapshot> mine, ghosts;  // scratch of the exchange
  std::size_t last_ghosts = 0;
  std::vector<std::uint32_t> plan_rows;
  double last_plan_ms = 0, last_avoidance_ms = 0;
  std::size_t last_plans = 0;
};

struct ScenarioSetup {
  bool use_cache = true;  // navigation mesh cache on disk
  std::size_t agents = 0; // 0: the scenario's counts; otherwise every group scaled so the total is about this
  SteeringParameters steering;  // the agents' steering (CrowdAgents::steering); read at spawn too (entrance_margin)
};

// Makes `crowd` (which must have no walkers yet) the scenario's: builds the navigation mesh and the obstacles, and spawns every group's agents
// standing at their spawn points facing their first goals (seeded from scenario.seed). A scenario with a track
// spawns the stadium lane walk instead (scene/spawn.h). Throws std::invalid_argument when the rig cannot walk,
// std::runtime_error when navigation cannot be built.
void set_scenario(Crowd& crowd, const Scenario& scenario, const ScenarioSetup& setup = {});

// The agents' stages of step(), before locomotion: navigation (steer, then the staggered plans) and avoidance
// (avoid, then move). No-ops for a crowd without agents.
void run_navigation_stage(Crowd& crowd, float dt);
void run_avoidance_stage(Crowd& crowd, float dt);

// True when every agent has reached its goal at least once.
bool all_agents_arrived(const Crowd& crowd);

}  // namespace strata
