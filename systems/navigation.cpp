#include "systems/navigation.h"

#include <algorithm>
#include <limits>
#include <cmath>
#include <optional>
#include <utility>

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "nav/navmesh.h"

namespace strata {
namespace {

std::uint32_t xorshift(std::uint32_t& s) {
  s ^= s << 13;
  s ^= s >> 17;
  s ^= s << 5;
  return s;
}
float uniform(std::uint32_t& s) { return static_cast<float>(xorshift(s) >> 8) * (1.0f / 16777216.0f); }

glm::vec2 random_in(glm::vec2 lo, glm::vec2 hi, std::uint32_t& rng) {
  const float u = uniform(rng), v = uniform(rng);
  return {lo.x + u * (hi.x - lo.x), lo.y + v * (hi.y - lo.y)};
}

glm::vec2 random_ground_point(glm::vec2 ground_min, glm::vec2 ground_max, std::uint32_t& rng) {
  const glm::vec2 inset(std::min(1.0f, 0.25f * (ground_max.x - ground_min.x)),
                        std::min(1.0f, 0.25f * (ground_max.y - ground_min.y)));
  return random_in(ground_min + inset, ground_max - inset, rng);
}

void set_goal(const SteerJob& job, std::size_t i, glm::vec2 goal) {
  const ColumnView<float>& a = job.agent;
  a.at(kAgentGoalX, i) = goal.x;
  a.at(kAgentGoalZ, i) = goal.y;
  a.at(kAgentTravelTime, i) = 0.0f;
  a.at(kAgentSinceProgress, i) = 0.0f;
  a.at(kAgentBestDistance, i) = std::hypot(goal.x - a.at(kAgentPx, i), goal.y - a.at(kAgentPz, i));
  job.corners.at(kAgentCorners * 2, i) = 0.0f;
  job.state.at(kAgentFlags, i) |= kAgentNeedsPath;
}

void steer_one(const SteerJob& job, std::size_t i) {
  const ColumnView<float>& a = job.agent;
  const ColumnView<float>& c = job.corners;
  const glm::vec2 pos(a.at(kAgentPx, i), a.at(kAgentPz, i));
  glm::vec2 goal(a.at(kAgentGoalX, i), a.at(kAgentGoalZ, i));
  const std::uint32_t group = std::min<std::uint32_t>(job.state.at(kAgentGroup, i),
                                                      static_cast<std::uint32_t>(job.goals.size() - 1));
  const ScenarioGoal& spec = job.goals[group];
  a.at(kAgentReplanIn, i) -= job.dt;

  // A region goal is reached on entering the region: the agent still walks on to its own point in it, but agents
  // standing at theirs would otherwise keep the last ones from ever reaching a point near them.
  if (spec.kind == GoalKind::Region && pos.x >= spec.region_min.x && pos.x <= spec.region_max.x &&
      pos.y >= spec.region_min.y && pos.y <= spec.region_max.y)
    job.state.at(kAgentFlags, i) |= kAgentArrived;
  const bool final_goal = spec.kind != GoalKind::Waypoints && spec.kind != GoalKind::Random;
  const bool arrived = (job.state.at(kAgentFlags, i) & kAgentArrived) != 0u;
  const float since = a.at(kAgentSinceProgress, i);
  // How far inside its region the agent is (0 outside; other goals have no edge to keep clear).
  const float depth = spec.kind == GoalKind::Region
                          ? std::max(0.0f, std::min({pos.x - spec.region_min.x, spec.region_max.x - pos.x,
                                                     pos.y - spec.region_min.y, spec.region_max.y - pos.y}))
                          : std::numeric_limits<float>::infinity();
  // A region goal and no headway: another point of the region, every settle_after seconds while that lasts.
  //  - Outside the region: the point it drew may be where an earlier agent settled (seen: the bottleneck's last
  //    walker pressing for ever against one who had stopped just inside the region, a metre from free floor).
  //    Since-progress is not reset, so an agent that still gets nowhere is reported stuck. Rejected: counting
  //    "near an occupied point" as arrival, which would let an agent that never entered the region arrive.
  //  - Inside it but within settle_depth of its edge: the new point lies at least settle_depth inside (where the
  //    region is that large). Settling there (below) walled the entrance off: in the bottleneck the first agents
  //    in stood along the region's near edge, everyone behind pressed against them for the rest of the run and the
  //    region's far side stayed empty.
  //  - Only near the region while outside it: a queue far from it (the bottleneck's room) makes no headway for
  //    long spells, and a new point there changes nothing but where the agent heads once through.
  const float outside = spec.kind == GoalKind::Region
                            ? glm::length(glm::clamp(pos, spec.region_min, spec.region_max) - pos)
                            : 0.0f;
  const bool redraw = spec.kind == GoalKind::Region && job.params.settle_after > 0.0f &&
                      (arrived ? depth < job.params.settle_depth : outside <= job.params.settle_depth);
  if (redraw) {
    if (since > job.params.settle_after &&
        std::floor(since / job.params.settle_after) != std::floor((since - job.dt) / job.params.settle_after)) {
      const glm::vec2 inset =
          arrived ? glm::min(glm::vec2(job.params.settle_depth), 0.5f * (spec.region_max - spec.region_min))
                  : glm::vec2(0.0f);
      std::uint32_t& rng = job.state.at(kAgentSeed, i);
      goal = random_in(spec.region_min + inset, spec.region_max - inset, rng);
      if (!arrived) goal = region_point_past_entrance(spec, goal, pos, job.params.entrance_margin);
      a.at(kAgentGoalX, i) = goal.x;
      a.at(kAgentGoalZ, i) = goal.y;
      a.at(kAgentBestDistance, i) = glm::length(goal - pos);
      c.at(kAgentCorners * 2, i) = 0.0f;
      job.state.at(kAgentFlags, i) |= kAgentNeedsPath;
    }
  } else if (final_goal && arrived && since > job.params.settle_after && glm::length(goal - pos) > 1e-3f) {
    // An agent that has reached its final goal (deep enough in its region) and makes no headway to its own point
    // stops there: two agents pressing for points behind each other wait for ever under reciprocal avoidance.
    goal = pos;
    a.at(kAgentGoalX, i) = pos.x;
    a.at(kAgentGoalZ, i) = pos.y;
    c.at(0, i) = pos.x;
    c.at(1, i) = pos.y;
    c.at(kAgentCorners * 2, i) = 1.0f;
  }
  // Arrival, and the next goal where the group has one.
  if (glm::length(goal - pos) < a.at(kAgentGoalRadius, i)) {
    job.state.at(kAgentFlags, i) |= kAgentArrived;
    if (spec.kind == GoalKind::Waypoints && spec.points.size() >= 2) {
      std::uint32_t& k = job.state.at(kAgentWaypoint, i);
      k = (k + 1) % static_cast<std::uint32_t>(spec.points.size());
      set_goal(job, i, spec.points[k]);
      goal = spec.points[k];
    } else if (spec.kind == GoalKind::Random) {
      std::uint32_t& rng = job.state.at(kAgentSeed, i);
      goal = random_ground_point(job.ground_min, job.ground_max, rng);
      ++job.state.at(kAgentWaypoint, i);
      set_goal(job, i, goal);
    } else {
      // Only a held agent's answer asks it to make way: a walking one's is its velocity, which on arrival still
      // points on along its way and would move its goal ahead of it.
      const bool asked = (job.state.at(kAgentFlags, i) & kAgentMakeWay) != 0u;
      const glm::vec2 aside(a.at(kAgentOrcaVx, i), a.at(kAgentOrcaVz, i));
      if (!(job.params.make_way_step > 0.0f && asked && glm::dot(aside, aside) > 0.25f)) {
        // A final goal: stand (the walk brings the feet together).
        a.at(kAgentPrefVx, i) = 0.0f;
        a.at(kAgentPrefVz, i) = 0.0f;
        a.at(kAgentTargetX, i) = goal.x;
        a.at(kAgentTargetZ, i) = goal.y;
        return;
      }
      // Someone walking is blocked against it: its standing spot moves aside (SteeringParameters::make_way_step),
      // at least a goal radius and a half, so it walks there rather than counting itself arrived where it is.
      const float step = std::max(job.params.make_way_step, 1.5f * a.at(kAgentGoalRadius, i));
      goal = pos + step * glm::normalize(aside);
      // In a region goal the new spot stays in the region (seen from above: agents that had made way stood just
      // past its side edges); at an edge that leaves it the part of the step along the edge.
      if (spec.kind == GoalKind::Region) goal = glm::clamp(goal, spec.region_min, spec.region_max);
      a.at(kAgentGoalX, i) = goal.x;
      a.at(kAgentGoalZ, i) = goal.y;
      a.at(kAgentBestDistance, i) = glm::length(goal - pos);
      a.at(kAgentSinceProgress, i) = 0.0f;
      c.at(0, i) = goal.x;
      c.at(1, i) = goal.y;
      c.at(kAgentCorners * 2, i) = 1.0f;
      job.state.at(kAgentFlags, i) &= ~kAgentMakeWay;
    }
  }

  // Corners passed. The last corner is the goal (or the mesh point nearest it) and is kept until arrival.
  auto count = static_cast<std::uint32_t>(std::clamp(c.at(kAgentCorners * 2, i), 0.0f, float(kAgentCorners)));
  while (count > 1 && glm::length(glm::vec2(c.at(0, i), c.at(1, i)) - pos) < job.params.corner_reached) {
    for (std::uint32_t k = 0; k + 1 < count; ++k) {
      c.at(2 * k, i) = c.at(2 * k + 2, i);
      c.at(2 * k + 1, i) = c.at(2 * k + 3, i);
    }
    --count;
    c.at(kAgentCorners * 2, i) = static_cast<float>(count);
    // The plan kept only the first corners; running low, ask for the rest.
    if (count == 1 && glm::length(glm::vec2(c.at(0, i), c.at(1, i)) - goal) > 0.05f)
      job.state.at(kAgentFlags, i) |= kAgentNeedsPath;
  }
  // Without a path yet (just spawned, or a new goal this step): straight at the goal until the planner answers.
  const glm::vec2 target = count > 0 ? glm::vec2(c.at(0, i), c.at(1, i)) : goal;
  const bool final_leg = count <= 1;
  a.at(kAgentTargetX, i) = target.x;
  a.at(kAgentTargetZ, i) = target.y;
  const glm::vec2 to = target - pos;
  const float distance = glm::length(to);
  float speed = a.at(kAgentPrefSpeed, i);
  if (final_leg && spec.kind != GoalKind::Waypoints && spec.kind != GoalKind::Random)
    speed *= std::clamp(distance / job.params.slow_radius, 0.0f, 1.0f);
  glm::vec2 wish = distance > 1e-4f ? to * (speed / distance) : glm::vec2(0.0f);
  // A small seeded wobble of the wished direction breaks the symmetric standoffs reciprocal avoidance is prone to
  // (two agents meeting exactly head-on, a ring converging on its centre), where every agent's best answer is to
  // wait for the others.
  if (job.params.wobble > 0.0f && distance > 1e-4f) {
    std::uint32_t& rng = job.state.at(kAgentSeed, i);
    // Stronger the longer it has made no headway (up to 4x after 3 s), so a standoff does not last.
    const float wobble = job.params.wobble * (1.0f + std::min(a.at(kAgentSinceProgress, i) / 1.0f, 3.0f));
    const float angle = wobble * (2.0f * uniform(rng) - 1.0f);
    const float c = std::cos(angle), s = std::sin(angle);
    wish = {c * wish.x - s * wish.y, s * wish.x + c * wish.y};
  }
  // Accelerating from the last preferred speed, not from the velocity avoidance allowed: in a crowd avoidance
  // slows everyone for a moment, and wishes limited to that slower speed kept the whole crowd crawling (the
  // bottleneck emptied at 0.13 agents a second).
  const float last_pref = std::hypot(a.at(kAgentPrefVx, i), a.at(kAgentPrefVz, i));
  const float heading = wish_heading(a.at(kAgentHeading, i), {a.at(kAgentVx, i), a.at(kAgentVz, i)},
                                     {a.at(kAgentPrefVx, i), a.at(kAgentPrefVz, i)}, to, job.body);
  const glm::vec2 pref = followable_velocity(wish, heading, last_pref, job.body, job.dt);
  a.at(kAgentPrefVx, i) = pref.x;
  a.at(kAgentPrefVz, i) = pref.y;
}

bool agent_views_fit(const ColumnView<float>& agent, const ColumnView<std::uint32_t>& state,
                     const ColumnView<float>& corners) {
  const std::size_t n = agent.count;
  return agent.fits(n, kAgentFloats) && state.fits(n, kAgentInts) && corners.fits(n, kAgentCorners * 2 + 1) &&
         !agent.overlaps(corners) && !agent.overlaps(state) && !corners.overlaps(state);
}

}  // namespace

glm::vec2 region_point_past_entrance(const ScenarioGoal& goal, glm::vec2 drawn, glm::vec2 from, float entrance_margin) {
  if (goal.kind != GoalKind::Region || !(entrance_margin > 0.0f)) return drawn;
  const glm::vec2 way = 0.5f * (goal.region_min + goal.region_max) - from;
  const int axis = std::abs(way.x) >= std::abs(way.y) ? 0 : 1;
  const float lo = goal.region_min[axis], hi = goal.region_max[axis], extent = hi - lo;
  if (!(extent > 2.0f * entrance_margin)) return drawn;
  const float within = std::clamp((drawn[axis] - lo) / extent, 0.0f, 1.0f);
  const float usable = extent - entrance_margin;
  glm::vec2 out = drawn;
  out[axis] = way[axis] >= 0.0f ? hi - (1.0f - within) * usable : lo + within * usable;
  return out;
}

glm::vec2 first_goal(const ScenarioGoal& goal, glm::vec2 spawn, glm::vec2 ground_min, glm::vec2 ground_max,
                     std::uint32_t& rng, std::uint32_t& waypoint, float entrance_margin) {
  waypoint = 0;
  switch (goal.kind) {
    case GoalKind::Point: return goal.points.empty() ? spawn : goal.points[0];
    case GoalKind::Opposite: return goal.points.empty() ? -spawn : 2.0f * goal.points[0] - spawn;
    case GoalKind::Region:
      return region_point_past_entrance(goal, random_in(goal.region_min, goal.region_max, rng), spawn, entrance_margin);
    case GoalKind::Random: return random_ground_point(ground_min, ground_max, rng);
    case GoalKind::Waypoints: {
      float best = 1e30f;
      for (std::size_t k = 0; k < goal.points.size(); ++k) {
        const float d = glm::length(goal.points[k] - spawn);
        if (d < best) {
          best = d;
          waypoint = static_cast<std::uint32_t>(k);
        }
      }
      return goal.points.empty() ? spawn : goal.points[waypoint];
    }
  }
  return spawn;
}

bool SteerJob::validate() const {
  if (!agent_views_fit(agent, state, corners) || goals.empty() || !std::isfinite(dt) || dt < 0.0f) return false;
  if (!(params.corner_reached > 0.0f) || !(params.slow_radius > 0.0f) || !(params.replan_period > 0.0f)) return false;
  if (!(ground_max.x > ground_min.x) || !(ground_max.y > ground_min.y)) return false;
  for (const ScenarioGoal& g : goals)
    if ((g.kind == GoalKind::Waypoints && g.points.size() < 2) || !(g.arrive_radius > 0.0f)) return false;
  return true;
}

bool SteerJob::run() const {
  if (!validate()) return false;
  constexpr std::size_t kChunk = 512;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, agent.count, kChunk),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i < r.end(); ++i) steer_one(*this, i);
                    },
                    tbb::simple_partitioner());
  return true;
}

bool PlanJob::validate() const {
  if (!query || !agent_views_fit(agent, state, corners) || goals.empty() || !(replan_period > 0.0f)) return false;
  return std::all_of(rows.begin(), rows.end(), [&](std::uint32_t r) { return r < agent.count; });
}

bool PlanJob::run() const {
  if (!validate()) return false;
  for (const std::uint32_t i : rows) {
    const glm::vec2 pos(agent.at(kAgentPx, i), agent.at(kAgentPz, i));
    glm::vec2 goal(agent.at(kAgentGoalX, i), agent.at(kAgentGoalZ, i));
    // What is left of the way as the agent knew it (straight on past the corners it kept, or straight to the goal
    // before its first path): progress is counted along the way it knows (agent_move), so a longer way learnt now
    // (a detour round an obstacle, corners beyond those kept, a goal moved) raises the nearest-so-far by as much.
    // Without this a walker going round the plaza's fountain at full speed made no "progress" until it had walked
    // off the detour, was counted stuck after 5 s, and its wish wobbled four times as hard (SteeringParameters::wobble).
    // Only the path's own increase is added: a body pushed back meanwhile has not come nearer.
    const float known_before = agent_path_distance(ColumnView<const float>(agent), ColumnView<const float>(corners), i);
    // A random goal drawn on an obstacle (or in its margin) is drawn again, a few times: snapped to the obstacle's
    // edge instead, every agent whose point fell on the plaza's fountain queued round its rim.
    const std::uint32_t group = std::min<std::uint32_t>(state.at(kAgentGroup, i), static_cast<std::uint32_t>(goals.size() - 1));
    if (goals[group].kind == GoalKind::Random && ground_max.x > ground_min.x && ground_max.y > ground_min.y) {
      std::uint32_t& rng = state.at(kAgentSeed, i);
      for (int attempt = 0; attempt < 8; ++attempt) {
        const std::optional<glm::vec2> on = query->nearest_walkable(goal, 0.05f);
        if (on && glm::length(*on - goal) < 0.05f) break;
        goal = random_ground_point(ground_min, ground_max, rng);
      }
      agent.at(kAgentGoalX, i) = goal.x;
      agent.at(kAgentGoalZ, i) = goal.y;
    }
    const NavPath path = query->find_path(pos, goal, kAgentCorners);
    std::uint32_t& flags = state.at(kAgentFlags, i);
    flags &= ~(kAgentNeedsPath | kAgentPartialPath);
    if (!path.complete) flags |= kAgentPartialPath;
    if (!path.corners.empty() && path.corners.size() < kAgentCorners &&
        glm::length(path.corners.back() - goal) > 0.01f && glm::length(path.corners.back() - goal) < 2.0f) {
      // The goal lies just off the walkable mesh (inside an obstacle's margin, or a random point drawn on one) and
      // the path ends at the mesh point nearest it: as good a goal, and an agent asked for a point it cannot stand
      // on would never arrive. Further off, the goal stays, and the agent is rightly reported stuck.
      goal = path.corners.back();
      agent.at(kAgentGoalX, i) = goal.x;
      agent.at(kAgentGoalZ, i) = goal.y;
      flags &= ~kAgentPartialPath;
    }
    const std::size_t n = std::min<std::size_t>(path.corners.size(), kAgentCorners);
    for (std::size_t k = 0; k < n; ++k) {
      corners.at(static_cast<std::uint32_t>(2 * k), i) = path.corners[k].x;
      corners.at(static_cast<std::uint32_t>(2 * k + 1), i) = path.corners[k].y;
    }
    corners.at(kAgentCorners * 2, i) = static_cast<float>(n);
    agent.at(kAgentReplanIn, i) = replan_period;
    const float known_now = agent_path_distance(ColumnView<const float>(agent), ColumnView<const float>(corners), i);
    if (known_now > known_before) agent.at(kAgentBestDistance, i) += known_now - known_before;
  }
  return true;
}

SteerJob make_steer_job(SoaTable& walkers, std::span<const ScenarioGoal> goals, glm::vec2 ground_min,
                        glm::vec2 ground_max, const SteeringParameters& params, const AgentMoveParameters& body,
                        float dt) {
  SteerJob job;
  job.agent = f32_view(walkers, kWalkerAgent);
  job.state = u32_view(walkers, kWalkerAgentState);
  job.corners = f32_view(walkers, kWalkerAgentCorners);
  job.goals = goals;
  job.ground_min = ground_min;
  job.ground_max = ground_max;
  job.params = params;
  job.body = body;
  job.dt = dt;
  return job;
}

PlanJob make_plan_job(SoaTable& walkers, NavQuery& query, std::span<const std::uint32_t> rows,
                      std::span<const ScenarioGoal> goals, glm::vec2 ground_min, glm::vec2 ground_max,
                      float replan_period) {
  PlanJob job;
  job.query = &query;
  job.agent = f32_view(walkers, kWalkerAgent);
  job.state = u32_view(walkers, kWalkerAgentState);
  job.corners = f32_view(walkers, kWalkerAgentCorners);
  job.rows = rows;
  job.goals = goals;
  job.ground_min = ground_min;
  job.ground_max = ground_max;
  job.replan_period = replan_period;
  return job;
}

}  // namespace strata
