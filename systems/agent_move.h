#pragma once
// Agent motion: moves each steered agent with exactly the velocity avoidance chose (its collision-free guarantee
// holds for that velocity and no other) and turns the body at a limited rate (GaitStyle::turn_rate) towards where it
// wants to go, or, carried at a walking pace not far off the way to its target, towards where it goes
// (facing_direction below; turning on the spot when nearly still). What makes the motion one a body can walk is
// upstream: navigation's preferred velocity goes through followable_velocity below (turning, slowing while facing
// away, acceleration and braking limits), and avoidance departs from it only to avoid someone. A walker standing
// (kGaitIdle > 0, systems/locomotion.h) is held still until it has left its stance (avoidance knows it will be:
// AvoidanceJob::holds, scene/crowd_agents.cpp). Also keeps the bookkeeping
// `report crowd` reads: time travelling, and time since the agent last came nearer its goal along its path (stuck
// detection).
//
// Rejected: limiting avoidance's velocity here (the body turning and accelerating after it). The velocity then
// left the set avoidance had proved collision-free, and a 24-agent circle overlapped by 10 cm.
//
//   reads:  agent (avoidance velocity, preferred velocity, position, heading, steering target, goal, corners),
//           gait (idle; each leg's swinging flag and planted heading), dt
//   writes: agent (position, velocity, heading, best distance, time since progress, travel time)
#include <cmath>
#include <cstddef>
#include <cstdint>

#include <glm/vec2.hpp>

#include "ecs/column_view.h"
#include "systems/locomotion.h"

namespace strata {

// `a` wrapped into [-pi, pi] (headings and turns about +Y).
inline float wrap_angle(float a) {
  constexpr float kTwoPi = 6.28318530718f;
  return a - kTwoPi * std::round(a / kTwoPi);
}

// How fast a body turns at `speed` (m/s): `in_place` standing, rising to `walking` at 1 m/s and above. A planted
// foot stays planted while the body turns over it, and the hip, knee and ankle twist at most ~1.2 rad between
// them; stepping on the spot is slower (longer stances), so the body must turn slower there.
inline float turn_rate_at(float speed, float walking, float in_place) {
  const float u = speed < 1.0f ? (speed > 0.0f ? speed : 0.0f) : 1.0f;
  return in_place + (walking - in_place) * u;
}

// Whether agent_move holds an agent still this step whatever avoidance answers: its walker is leaving or settling
// into its idle stance (kGaitIdle > 0), its feet down side by side. The avoidance gather tells ORCA the same
// (AvoidanceJob::holds, scene/crowd_agents.cpp), so both read this one rule.
inline bool agent_held_still(float gait_idle) { return gait_idle > 0.0f; }

// Where a walking body faces: where it wants to go (`preferred`), or, carried by avoidance at a walking pace
// within `side_angle` of the way to its steering target (`to_target`; the preferred velocity when that is zero),
// where it goes. Pushed aside or back it steps that way without turning round: facing its velocity whatever it was
// made pushed agents turn their backs on their goal and take seconds to turn back (half a test room never reached
// its door). But a body facing its goal while avoidance carried it across at 1.3-1.4 m/s (the crossing's jams)
// walked sideways on a forward gait, its feet planted 0.6 m off the line it went along, and dragged. Measured
// against the target, not the preferred velocity: navigation turns the wish from the body's heading at the turn
// rate (followable_velocity), so a body facing a crowd's flow wished along it, faced it, and was carried into the
// other group's goal region (3 of the crossing's 200 never arrived). Carried further off than side_angle, it faces
// its wish turned towards the line it goes along just far enough that it is carried across itself at no more than
// `side_speed` (side_step_turn; 0 turns that off): no forward gait steps sideways at 1.2 m/s, the crossing's other
// stream. Wanting nothing, it faces where it goes. Zero when neither has a direction.
glm::vec2 facing_direction(glm::vec2 velocity, glm::vec2 preferred, glm::vec2 to_target, float walking_speed,
                           float side_angle, float side_speed = 0.0f);
// facing_direction's first rule: whether the body faces its velocity (carried at walking_speed or faster within
// side_angle of the way to its target, or moving without a wish).
bool faces_velocity(glm::vec2 velocity, glm::vec2 preferred, glm::vec2 to_target, float walking_speed,
                    float side_angle);
// facing_direction's second rule: how far (rad, signed as headings) the body turns from its wish towards the line
// of its velocity so that it is carried across itself at no more than side_speed; 0 when it already is.
float side_step_turn(glm::vec2 velocity, glm::vec2 preferred, float side_speed);

struct AgentMoveParameters {
  // The walk's own values (GaitStyle), which the walk predicts footprints and turns the body with: a crowd takes
  // them from its style (of() below), and the defaults are GaitStyle's defaults, so there is one source for each.
  float turn_rate = GaitStyle{}.turn_rate;                    // rad/s, walking
  float turn_in_place_rate = GaitStyle{}.turn_in_place_rate;  // rad/s, standing
  float acceleration = GaitStyle{}.agent_acceleration;        // m/s^2 when speeding up
  float braking = GaitStyle{}.agent_braking;                  // m/s^2 when slowing down
  // facing_direction: from this speed (m/s) a body carried within face_side_angle (rad) of where it wants to go
  // faces its velocity.
  float face_velocity_speed = GaitStyle{}.face_velocity_speed;
  float face_side_angle = GaitStyle{}.face_side_angle;
  float face_side_speed = GaitStyle{}.face_side_speed;
  float stance_twist = GaitStyle{}.stance_twist;
  float start_speed = 0.15f;   // m/s a standing body may start at (above GaitStyle::stand_speed)
  float progress_step = 0.25f; // m: coming this much nearer the goal counts as progress

  // The walk's values of `style`, the rest as above. A test or tool that changes the style re-derives these.
  static AgentMoveParameters of(const GaitStyle& style) {
    AgentMoveParameters p;
    p.turn_rate = style.turn_rate;
    p.turn_in_place_rate = style.turn_in_place_rate;
    p.acceleration = style.agent_acceleration;
    p.braking = style.agent_braking;
    p.face_velocity_speed = style.face_velocity_speed;
    p.face_side_angle = style.face_side_angle;
    p.face_side_speed = style.face_side_speed;
    p.stance_twist = style.stance_twist;
    return p;
  }
};

// The part of a body's `turn` (rad, signed as headings) it can make over a foot planted at `plant_heading` while
// the other foot swings: the foot's twist under the body (heading less plant heading) grows no further than
// `limit`, nor than it already is. Turns that untwist it are whole. People turn by stepping; on one foot the hip,
// knee and ankle twist at most ~0.9 rad between them, and the foot cannot lift until the other is down.
float stance_limited_turn(float heading, float turn, float plant_heading, float limit);

// The velocity a walking body can take up this step on its way to `wish`: turned from its heading by at most its
// turn rate, slowed while it faces away (to a stop past 90 degrees: it turns on the spot), within acceleration and
// braking limits of its current `speed`, never faster than the wish. Navigation passes its preferred velocity
// through this (systems/navigation.h), so avoidance starts from a velocity the body can follow.
glm::vec2 followable_velocity(glm::vec2 wish, float heading, float speed, const AgentMoveParameters& params, float dt);

// The heading navigation turns the wish from (followable_velocity): the body's, less the turn it made only to keep
// its feet under a sideways carry (side_step_turn, from the last step's velocity and preferred velocity). That turn
// is the feet's, not a change of mind: counted, it dragged the wish along the carry (the wish turns from the heading
// at the turn rate and slows while it faces away), and a walker swept by a crowd's flow drifted on with it.
float wish_heading(float heading, glm::vec2 velocity, glm::vec2 last_preferred, glm::vec2 to_target,
                   const AgentMoveParameters& params);

struct AgentMoveJob {
  ColumnView<float> agent;                   // kAgentFloats, read and written
  ColumnView<const float> corners;           // kAgentCorners * 2 + 1
  ColumnView<const float> gait;              // kGaitFloats (kGaitIdle, kLegSwinging, kLegPlantHeading read)
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
