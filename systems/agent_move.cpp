#include "systems/agent_move.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "components/walker.h"

namespace strata {
namespace {

void move_one(const AgentMoveJob& job, std::size_t i) {
  const ColumnView<float>& a = job.agent;
  const float dt = job.dt;
  const AgentMoveParameters& p = job.params;
  float vx = a.at(kAgentOrcaVx, i), vz = a.at(kAgentOrcaVz, i);
  // Leaving (or settling into) the idle stance: the feet are down side by side and the body waits for them, turning
  // no more than it moves. A standing body that turned towards a wish too slow to walk twisted its legs over flat feet
  // (which never pivot) until IK's clamp slid the toes: 12 cm in a test turning a quarter round, up to 3 cm at the
  // crossing's arrivals. It turns by stepping, once the wish is enough to leave the stance.
  const bool held = agent_held_still(job.gait.at(kGaitIdle, i));
  if (held) vx = vz = 0.0f;
  const float speed = std::hypot(vx, vz);
  const glm::vec2 face = facing_direction({vx, vz}, {a.at(kAgentPrefVx, i), a.at(kAgentPrefVz, i)},
                                          {a.at(kAgentTargetX, i) - a.at(kAgentPx, i), a.at(kAgentTargetZ, i) - a.at(kAgentPz, i)},
                                          p.face_velocity_speed, p.face_side_angle, p.face_side_speed);
  float heading = a.at(kAgentHeading, i);
  if (!held && (face.x != 0.0f || face.y != 0.0f)) {
    const float most = turn_rate_at(speed, p.turn_rate, p.turn_in_place_rate) * dt;
    float turn = std::clamp(wrap_angle(std::atan2(face.x, face.y) - heading), -most, most);
    // On one foot the body turns only as far as that foot's twist allows (stance_limited_turn). Predicting the
    // turn into each footprint's heading was not enough: a slow walker's stance lasts 0.9 s, and a wish that keeps
    // turning (a walker stepping round another) turned the body up to 1.0 rad over a foot planted for less.
    for (int leg = 0; leg < 2; ++leg) {
      const auto c = [&](int l, std::uint32_t k) {
        return job.gait.at(kGaitLegs + static_cast<std::uint32_t>(l) * kLegFloats + k, i);
      };
      if (c(leg, kLegSwinging) < 0.5f && c(1 - leg, kLegSwinging) > 0.5f)
        turn = stance_limited_turn(heading, turn, c(leg, kLegPlantHeading), p.stance_twist);
    }
    heading = wrap_angle(heading + turn);
  }
  a.at(kAgentVx, i) = vx;
  a.at(kAgentVz, i) = vz;
  a.at(kAgentPx, i) += vx * dt;
  a.at(kAgentPz, i) += vz * dt;
  a.at(kAgentHeading, i) = heading;

  // Progress bookkeeping. An agent that has arrived and stands is not stuck.
  a.at(kAgentTravelTime, i) += dt;
  const float remaining = agent_path_distance(ColumnView<const float>(a), job.corners, i);
  const bool arrived = (job.state.at(kAgentFlags, i) & kAgentArrived) != 0u &&
                       std::hypot(a.at(kAgentGoalX, i) - a.at(kAgentPx, i), a.at(kAgentGoalZ, i) - a.at(kAgentPz, i)) <
                           a.at(kAgentGoalRadius, i);
  if (arrived || remaining < a.at(kAgentBestDistance, i) - p.progress_step) {
    a.at(kAgentBestDistance, i) = remaining;
    a.at(kAgentSinceProgress, i) = 0.0f;
  } else {
    a.at(kAgentSinceProgress, i) += dt;
  }
}

}  // namespace

namespace {
constexpr float kDirectionless = 0.05f;  // m/s: slower than this, a velocity or wish has no direction
}  // namespace

float stance_limited_turn(float heading, float turn, float plant_heading, float limit) {
  const float before = wrap_angle(heading - plant_heading), after = before + turn;
  if (std::abs(after) <= limit || std::abs(after) <= std::abs(before)) return turn;
  return std::copysign(std::max(limit, std::abs(before)), after) - before;
}

bool faces_velocity(glm::vec2 velocity, glm::vec2 preferred, glm::vec2 to_target, float walking_speed,
                    float side_angle) {
  const float pref = std::hypot(preferred.x, preferred.y), speed = std::hypot(velocity.x, velocity.y);
  if (pref < kDirectionless) return speed >= kDirectionless;
  const float target = std::hypot(to_target.x, to_target.y);
  const glm::vec2 way = target > 1e-4f ? to_target / target : preferred / pref;
  return speed >= walking_speed && velocity.x * way.x + velocity.y * way.y >= std::cos(side_angle) * speed;
}

float side_step_turn(glm::vec2 velocity, glm::vec2 preferred, float side_speed) {
  const float pref = std::hypot(preferred.x, preferred.y), speed = std::hypot(velocity.x, velocity.y);
  if (!(side_speed > 0.0f) || pref < kDirectionless || !(speed > side_speed)) return 0.0f;
  const glm::vec2 wish = preferred / pref;
  const float along = velocity.x * wish.x + velocity.y * wish.y, across = wish.y * velocity.x - wish.x * velocity.y;
  if (std::abs(across) <= side_speed) return 0.0f;
  // Turn from the wish towards the velocity's line, forwards or backwards, whichever is nearer, until the
  // velocity's share across the body is side_speed.
  constexpr float kPi = 3.14159265f;
  const float theta = std::atan2(across, along);  // from the wish to the velocity, signed as headings are
  const float keep = std::asin(side_speed / speed);
  return std::abs(theta) <= 0.5f * kPi ? theta - std::copysign(keep, theta) : theta - std::copysign(kPi - keep, theta);
}

glm::vec2 facing_direction(glm::vec2 velocity, glm::vec2 preferred, glm::vec2 to_target, float walking_speed,
                           float side_angle, float side_speed) {
  const float pref = std::hypot(preferred.x, preferred.y), speed = std::hypot(velocity.x, velocity.y);
  if (pref < kDirectionless && speed < kDirectionless) return glm::vec2(0.0f);
  if (faces_velocity(velocity, preferred, to_target, walking_speed, side_angle)) return velocity;
  const float turn = side_step_turn(velocity, preferred, side_speed);
  if (turn == 0.0f) return preferred;
  // A heading h faces (sin h, cos h): turning by `turn` is this rotation.
  const float c = std::cos(turn), s = std::sin(turn);
  return {preferred.x * c + preferred.y * s, -preferred.x * s + preferred.y * c};
}

float wish_heading(float heading, glm::vec2 velocity, glm::vec2 last_preferred, glm::vec2 to_target,
                   const AgentMoveParameters& p) {
  if (faces_velocity(velocity, last_preferred, to_target, p.face_velocity_speed, p.face_side_angle)) return heading;
  return wrap_angle(heading - side_step_turn(velocity, last_preferred, p.face_side_speed));
}

float agent_path_distance(const ColumnView<const float>& agent, const ColumnView<const float>& corners, std::size_t i) {
  const float px = agent.at(kAgentPx, i), pz = agent.at(kAgentPz, i);
  const auto count = static_cast<std::uint32_t>(std::clamp(corners.at(kAgentCorners * 2, i), 0.0f,
                                                           static_cast<float>(kAgentCorners)));
  float d = 0.0f, x = px, z = pz;
  for (std::uint32_t c = 0; c < count; ++c) {
    const float cx = corners.at(2 * c, i), cz = corners.at(2 * c + 1, i);
    d += std::hypot(cx - x, cz - z);
    x = cx;
    z = cz;
  }
  // Beyond the corners kept (or with none): straight on to the goal.
  return d + std::hypot(agent.at(kAgentGoalX, i) - x, agent.at(kAgentGoalZ, i) - z);
}

glm::vec2 followable_velocity(glm::vec2 wish, float heading, float speed, const AgentMoveParameters& p, float dt) {
  const float wish_speed = std::hypot(wish.x, wish.y);
  if (!(wish_speed > 1e-4f)) return {0.0f, 0.0f};
  const float want = std::atan2(wish.x, wish.y);
  const float most = turn_rate_at(speed, p.turn_rate, p.turn_in_place_rate) * dt;
  const float direction = wrap_angle(heading + std::clamp(wrap_angle(want - heading), -most, most));
  // Facing away from where it should go, it slows (to a stop past 90 degrees) while it turns.
  // Facing away, it still creeps at start_speed in the direction it has turned to: that keeps it stepping round on
  // the spot. A zero wish there made it stand, and a standing body never turned: agents facing a wall stayed so.
  float target = std::max(wish_speed * std::max(std::cos(wrap_angle(want - direction)), 0.0f),
                          std::min(wish_speed, p.start_speed));
  // From standing a first step starts at start_speed: limiting the wish to speed + a dt from rest kept it below the
  // speed at which a walker leaves its stance, and nobody ever set off.
  target = std::clamp(target, std::max(speed - p.braking * dt, 0.0f), std::max(speed, p.start_speed) + p.acceleration * dt);
  target = std::min(target, wish_speed);
  return {std::sin(direction) * target, std::cos(direction) * target};
}

bool AgentMoveJob::validate() const {
  const std::size_t n = agent.count;
  if (!agent.fits(n, kAgentFloats) || !corners.fits(n, kAgentCorners * 2 + 1) || !gait.fits(n, kGaitFloats) ||
      !state.fits(n, kAgentInts))
    return false;
  if (agent.overlaps(corners) || agent.overlaps(gait) || agent.overlaps(state)) return false;
  if (!std::isfinite(dt) || dt < 0.0f || !(params.turn_rate > 0.0f) || !(params.turn_in_place_rate > 0.0f) ||
      !(params.acceleration > 0.0f) || !(params.braking > 0.0f) || !(params.progress_step > 0.0f) ||
      !(params.stance_twist >= 0.0f))  // NaN too: a NaN limit would turn the heading to NaN
    return false;
  // A non-finite avoidance velocity would move the agent to NaN: refuse it rather than propagate.
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(agent.at(kAgentOrcaVx, i)) || !std::isfinite(agent.at(kAgentOrcaVz, i))) return false;
  return true;
}

bool AgentMoveJob::run() const {
  if (!validate()) return false;
  constexpr std::size_t kChunk = 512;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, agent.count, kChunk),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i < r.end(); ++i) move_one(*this, i);
                    },
                    tbb::simple_partitioner());
  return true;
}

AgentMoveJob make_agent_move_job(SoaTable& walkers, float dt, const AgentMoveParameters& params) {
  AgentMoveJob job;
  job.agent = f32_view(walkers, kWalkerAgent);
  job.corners = f32_view(std::as_const(walkers), kWalkerAgentCorners);
  job.gait = f32_view(std::as_const(walkers), kWalkerGait);
  job.state = u32_view(std::as_const(walkers), kWalkerAgentState);
  job.params = params;
  job.dt = dt;
  return job;
}

}  // namespace strata
