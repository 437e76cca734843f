#pragma once
// Agent motion: moves each steered agent with the velocity avoidance chose, as a body can. The agent walks where it
// faces and turns towards that velocity at a limited rate (GaitStyle::turn_rate), slowing while it faces away from
// it (a person turns before walking off, and turns on the spot rather than walking backwards), and its speed
// changes within acceleration and braking limits (GaitStyle::agent_acceleration, agent_braking). A walker standing (kGaitIdle > 0, systems/locomotion.h) is held still until it
// has left its stance. Also keeps the bookkeeping `report crowd` reads: time travelling, and time since the agent
// last came nearer its goal along its path (stuck detection).
//
// Avoidance's guarantee holds for the velocity it returns; a slower one in the same direction can fall outside it,
// which is why the frame script gives avoidance radii a small margin over the bodies' (scene/crowd_agents.h).
// Rejected: feeding these limits into the linear program as constraints; ORCA's 3-D fallback then fires whenever
// the limits and the half-planes disagree, and agents froze in dense crossings.
//
//   reads:  agent (avoidance velocity, position, velocity, heading, goal, corners), gait (idle), dt, parameters
//   writes: agent (position, velocity, heading, best distance, time since progress, travel time)
#include <cstddef>
#include <cstdint>

#include "ecs/column_view.h"

namespace strata {

// How fast a body turns at `speed` (m/s): `in_place` standing, rising to `walking` at 1 m/s and above. A planted
// foot stays planted while the body turns over it, and the hip, knee and ankle twist at most ~1.2 rad between
// them; stepping on the spot is slower (longer stances), so the body must turn slower there.
inline float turn_rate_at(float speed, float walking, float in_place) {
  const float u = speed < 1.0f ? (speed > 0.0f ? speed : 0.0f) : 1.0f;
  return in_place + (walking - in_place) * u;
}

struct AgentMoveParameters {
  // The walk's GaitStyle::turn_rate, turn_in_place_rate, agent_acceleration and agent_braking (the walk predicts
  // footprints with them).
  float turn_rate = 1.4f;      // rad/s, walking
  float turn_in_place_rate = 1.0f;  // rad/s, standing
  float acceleration = 1.2f;   // m/s^2 when speeding up
  float braking = 1.5f;        // m/s^2 when slowing down
  float progress_step = 0.25f; // m: coming this much nearer the goal counts as progress
};

struct AgentMoveJob {
  ColumnView<float> agent;                   // kAgentFloats, read and written
  ColumnView<const float> corners;           // kAgentCorners * 2 + 1
  ColumnView<const float> gait;              // kGaitFloats (kGaitIdle read)
  ColumnView<const std::uint32_t> state;     // kAgentInts (flags read)
  AgentMoveParameters params;
  float dt = 0.0f;

  bool validate() const;
  bool run() const;
};

AgentMoveJob make_agent_move_job(SoaTable& walkers, float dt, const AgentMoveParameters& params);

// An agent's distance to its goal along its remaining path corners (straight to the goal when it has none).
float agent_path_distance(const ColumnView<const float>& agent, const ColumnView<const float>& corners,
                          std::size_t i);

}  // namespace strata
