#include "scene/crowd_agents.h"

#include <algorithm>
#include <chrono>
#include <string>
#include <cmath>
#include <random>
#include <stdexcept>

#include "motion/track.h"
#include "scene/body_settings.h"
#include "scene/crowd.h"
#include "scene/spawn.h"
#include "systems/agent_move.h"
#include "systems/animation_sample.h"
#include "systems/job.h"
#include "systems/locomotion.h"

namespace strata {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr std::uint32_t kGhostRow = ~0u;  // CrowdAgents::order: an agent another process steers

// A normal draw from unit_float (scene/spawn.h), not std::normal_distribution, whose algorithm is
// implementation-defined: the same seed must place the same crowd with any standard library.
float normal(std::mt19937_64& rng) {
  const float u = std::max(unit_float(rng), 1e-7f), v = unit_float(rng);
  return std::sqrt(-2.0f * std::log(u)) * std::cos(2.0f * kPi * v);
}

// Spawn points of a group: evenly on its circle, or a jittered grid over its rectangle that keeps agents at least
// two radii apart.
std::vector<glm::vec2> spawn_points(const SpawnGroup& g, std::uint32_t count, float radius, std::mt19937_64& rng) {
  std::vector<glm::vec2> out;
  out.reserve(count);
  if (g.shape == SpawnShape::Circle) {
    for (std::uint32_t k = 0; k < count; ++k) {
      const float a = 2.0f * kPi * static_cast<float>(k) / static_cast<float>(count);
      out.push_back(g.center + g.radius * glm::vec2(std::cos(a), std::sin(a)));
    }
    return out;
  }
  const glm::vec2 size = g.max - g.min;
  const float aspect = size.y > 0.0f ? size.x / size.y : 1.0f;
  const auto cols = static_cast<std::uint32_t>(std::max(1.0f, std::ceil(std::sqrt(static_cast<float>(count) * aspect))));
  const std::uint32_t rows = (count + cols - 1) / cols;
  const glm::vec2 cell(size.x / static_cast<float>(cols), size.y / static_cast<float>(rows));
  const glm::vec2 jitter(std::max(0.0f, 0.5f * cell.x - radius * 1.05f), std::max(0.0f, 0.5f * cell.y - radius * 1.05f));
  for (std::uint32_t k = 0; k < count; ++k) {
    const glm::vec2 centre = g.min + cell * glm::vec2(static_cast<float>(k % cols) + 0.5f, static_cast<float>(k / cols) + 0.5f);
    out.push_back(centre + jitter * glm::vec2(2.0f * unit_float(rng) - 1.0f, 2.0f * unit_float(rng) - 1.0f));
  }
  return out;
}

Entity spawn_agent(Crowd& crowd, std::uint32_t group, glm::vec2 at, glm::vec2 goal, std::uint32_t waypoint,
                   std::uint32_t seed, float height, float speed, const CrowdAgents& agents) {
  const CrowdMotion& m = crowd.motion;
  const Entity e = spawn_clip_walker(crowd, glm::vec3(at.x, 0.0f, at.y), 0.0f, 0.0f, 1.0f, kRestPose);
  const EntityLocation loc = crowd.world.location(e);
  SoaTable& t = crowd.world.table(loc.table);
  const std::size_t b = loc.block;
  const glm::vec2 to = goal - at;
  const float heading = glm::length(to) > 1e-4f ? std::atan2(to.x, to.y) : 0.0f;
  const ScenarioGoal& spec = agents.goals[group];
  const std::pair<std::uint32_t, float> agent_values[] = {
      {kAgentPx, at.x}, {kAgentPz, at.y}, {kAgentHeading, heading}, {kAgentRadius, agents.scenario.agents.radius},
      {kAgentPrefSpeed, speed}, {kAgentGoalX, goal.x}, {kAgentGoalZ, goal.y}, {kAgentGoalRadius, spec.arrive_radius},
      {kAgentTargetX, goal.x}, {kAgentTargetZ, goal.y}, {kAgentBestDistance, glm::length(to)}};
  for (const auto& [component, value] : agent_values) t.f32(kWalkerAgent, component)[b] = value;
  t.u32(kWalkerAgentState, kAgentGroup)[b] = group;
  t.u32(kWalkerAgentState, kAgentWaypoint)[b] = waypoint;
  t.u32(kWalkerAgentState, kAgentFlags)[b] = kAgentNeedsPath;
  t.u32(kWalkerAgentState, kAgentSeed)[b] = seed | 1u;
  // Standing at the start, feet together: the walk starts when the agent first moves.
  const float cadence = m.style.agent_min_cadence;
  const std::pair<std::uint32_t, float> gait_values[] = {
      {kGaitCadence, cadence}, {kGaitCadenceTarget, cadence}, {kGaitHeight, height}, {kGaitIdle, 1.0f}};
  for (const auto& [component, value] : gait_values) t.f32(kWalkerGait, component)[b] = value;
  run_or_throw(make_start_walking_job(*m.locomotion, m.paths, t, b, m.style, true), "start_walking");
  const DetailSlot start = spawn_slot(crowd);
  if (start == DetailSlot::Impostor) crowd.world.move(e, crowd.tables[slot_index(start)]);
  return e;
}

template <class F>
void for_each_agent_table(Crowd& crowd, F&& f) {
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    SoaTable& t = crowd.world.table(crowd.tables[s]);
    if (t.size() > 0) f(t, static_cast<std::uint32_t>(s));
  }
}

}  // namespace

void set_scenario(Crowd& crowd, const Scenario& scenario, const ScenarioSetup& setup) {
  CrowdMotion& m = crowd.motion;
  if (!m.locomotion) throw std::invalid_argument("scenario '" + scenario.name + "': the rig cannot walk: " + m.walk_error);
  if (scenario.has_track) {
    // The original lane walk, as one scenario.
    CrowdConfig config;
    config.motion = MotionSource::Walk;
    config.walkers = setup.agents > 0 ? setup.agents : scenario.track.walkers;
    config.seed = scenario.seed;
    config.track_straight = scenario.track.straight;
    config.track_radius = scenario.track.radius;
    config.lane_spacing = scenario.track.lane_spacing;
    config.speed_min = scenario.track.speed_min;
    config.speed_max = scenario.track.speed_max;
    config.style = m.style;
    crowd.agents.reset();
    spawn_crowd(crowd, config);
    return;
  }
  crowd.widen_for_agents();
  auto agents = std::make_unique<CrowdAgents>();
  agents->scenario = scenario;
  agents->steering = setup.steering;
  for (const SpawnGroup& g : scenario.groups) agents->goals.push_back(g.goal);
  if (agents->goals.empty()) throw std::invalid_argument("scenario '" + scenario.name + "' has no spawn group");
  const auto start = std::chrono::steady_clock::now();
  NavBuildSettings nav;
  nav.agent_radius = scenario.agents.radius;
  agents->navmesh = NavMesh::build(scenario, nav, setup.use_cache);
  agents->navigation_build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  agents->query = std::make_unique<NavQuery>(*agents->navmesh);
  std::vector<std::vector<glm::vec2>> polygons;
  for (const ScenarioPolygon& p : scenario.obstacles) polygons.push_back(p.points);
  agents->obstacles = std::make_unique<ObstacleSet>(polygons);
  agents->move = AgentMoveParameters::of(m.style);
  m.source = MotionSource::Walk;
  const CrowdAgents& a = *agents;
  crowd.agents = std::move(agents);

  const std::size_t total = scenario.agent_count();
  const double scale = setup.agents > 0 && total > 0 ? static_cast<double>(setup.agents) / static_cast<double>(total) : 1.0;
  std::mt19937_64 rng(scenario.seed);
  const AgentParameters& p = scenario.agents;
  for (std::uint32_t group = 0; group < scenario.groups.size(); ++group) {
    const SpawnGroup& g = scenario.groups[group];
    const auto count = static_cast<std::uint32_t>(std::max(1.0, std::round(g.count * scale)));
    const std::vector<glm::vec2> points = spawn_points(g, count, p.radius, rng);
    crowd.table(spawn_slot(crowd)).reserve(crowd.table(spawn_slot(crowd)).size() + count);
    for (const glm::vec2& at : points) {
      auto seed = static_cast<std::uint32_t>(rng() >> 32);
      std::uint32_t waypoint = 0;
      std::uint32_t goal_rng = seed | 1u;
      const glm::vec2 goal = first_goal(g.goal, at, scenario.ground_min, scenario.ground_max, goal_rng, waypoint,
                                        a.steering.entrance_margin);
      const float height = std::clamp(p.height_mean + p.height_sd * normal(rng), p.height_mean - 3.0f * p.height_sd,
                                      p.height_mean + 3.0f * p.height_sd);
      const float speed = std::clamp(p.speed_mean + p.speed_sd * normal(rng), p.speed_min, p.speed_max);
      spawn_agent(crowd, group, at, goal, waypoint, goal_rng, height, speed, a);
    }
  }
}

void run_navigation_stage(Crowd& crowd, float dt) {
  if (!crowd.agents) return;
  CrowdAgents& a = *crowd.agents;
  const Scenario& sc = a.scenario;
  for_each_agent_table(crowd, [&](SoaTable& t, std::uint32_t) {
    run_or_throw(make_steer_job(t, a.goals, sc.ground_min, sc.ground_max, a.steering, a.move, dt), "steer");
  });
  // Staggered planning: those without a path first, then the most overdue; ties by entity index, so the choice
  // is the same whatever table a walker sits in.
  const auto start = std::chrono::steady_clock::now();
  a.candidates.clear();
  for_each_agent_table(crowd, [&](SoaTable& t, std::uint32_t slot) {
    const ColumnView<const float> agent = f32_view(std::as_const(t), kWalkerAgent);
    const ColumnView<const std::uint32_t> state = u32_view(std::as_const(t), kWalkerAgentState);
    for (std::size_t r = 0; r < t.size(); ++r) {
      if (!agent_wants_plan(agent, state, r)) continue;
      const bool none = (state.at(kAgentFlags, r) & kAgentNeedsPath) != 0u;
      a.candidates.push_back({none ? 1e9f : -agent.at(kAgentReplanIn, r), t.owner(static_cast<std::uint32_t>(r)).index,
                              slot, static_cast<std::uint32_t>(r)});
    }
  });
  std::size_t take = std::min<std::size_t>(a.candidates.size(), a.plans_per_step);
  std::partial_sort(a.candidates.begin(), a.candidates.begin() + static_cast<std::ptrdiff_t>(take), a.candidates.end(),
                    more_urgent);
  if (a.exchange) {
    // Spread over processes: the budget goes to the whole crowd's most urgent, of which this process plans its own.
    a.candidates.resize(take);
    a.exchange->select_plans(a.candidates, a.plans_per_step);
    take = a.candidates.size();
  }
  std::sort(a.candidates.begin(), a.candidates.begin() + static_cast<std::ptrdiff_t>(take),
            [](const auto& x, const auto& y) { return x.table != y.table ? x.table < y.table : x.walker < y.walker; });
  for (std::size_t k = 0; k < take;) {
    const std::uint32_t slot = a.candidates[k].table;
    a.plan_rows.clear();
    for (; k < take && a.candidates[k].table == slot; ++k) a.plan_rows.push_back(a.candidates[k].row);
    SoaTable& t = crowd.world.table(crowd.tables[slot]);
    run_or_throw(make_plan_job(t, *a.query, a.plan_rows, a.goals, sc.ground_min, sc.ground_max,
                               a.steering.replan_period),
                 "plan");
  }
  a.last_plans = take;
  a.last_plan_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void run_avoidance_stage(Crowd& crowd, float dt) {
  if (!crowd.agents) return;
  CrowdAgents& a = *crowd.agents;
  // Gather in entity order.
  a.rows.clear();
  for_each_agent_table(crowd, [&](SoaTable& t, std::uint32_t slot) {
    for (std::uint32_t r = 0; r < t.size(); ++r) a.rows.push_back({t.owner(r).index, slot, r});
  });
  // The entity index is read once per row, not twice per comparison (10,000 agents: ~270,000 comparisons a step).
  std::sort(a.rows.begin(), a.rows.end(),
            [](const CrowdAgents::Row& x, const CrowdAgents::Row& y) { return x.walker < y.walker; });
  a.mine.resize(a.rows.size());
  for (std::size_t k = 0; k < a.rows.size(); ++k) {
    const SoaTable& t = crowd.world.table(crowd.tables[a.rows[k].table]);
    const std::size_t r = a.rows[k].row;
    auto f = [&](std::uint32_t c) { return t.f32(kWalkerAgent, c)[r]; };
    const float scale = t.f32(kWalkerPlacement, 4)[r];
    a.mine[k] = {a.rows[k].walker, f(kAgentPx), f(kAgentPz), f(kAgentVx), f(kAgentVz), f(kAgentPrefVx),
                 f(kAgentPrefVz), f(kAgentRadius) + a.radius_margin, 1.25f * f(kAgentPrefSpeed),
                 t.f32(kWalkerGait, kGaitLagX)[r], t.f32(kWalkerGait, kGaitLagZ)[r],
                 a.tether_share * kBodyLagMax * scale, agent_held_still(t.f32(kWalkerGait, kGaitIdle)[r]) ? 1.0f : 0.0f};
  }
  // Spread over processes: the other processes' agents near this one's join in entity order (merged with this
  // process's, which win a tie: a walker nobody owns is kept by every process), so each of this process's agents
  // sees the neighbours, in the order, that one process would give it. Inputs whose `a.order` is kGhostRow are
  // ghosts: solved (their answers feed the second pass), never written back.
  a.ghosts.clear();
  if (a.exchange) {
    a.exchange->exchange_ghosts(a.mine, a.ghosts);
    std::sort(a.ghosts.begin(), a.ghosts.end(),
              [](const AgentSnapshot& x, const AgentSnapshot& y) { return x.walker < y.walker; });
    a.ghosts.erase(std::unique(a.ghosts.begin(), a.ghosts.end(),
                               [](const AgentSnapshot& x, const AgentSnapshot& y) { return x.walker == y.walker; }),
                   a.ghosts.end());
  }
  a.last_ghosts = a.ghosts.size();
  const std::size_t n = a.mine.size() + a.ghosts.size();
  for (auto* v : {&a.px, &a.pz, &a.vx, &a.vz, &a.pref_vx, &a.pref_vz, &a.radius, &a.max_speed, &a.new_vx, &a.new_vz,
                  &a.tether_dx, &a.tether_dz, &a.tether_reach})
    v->resize(n);
  a.holds.resize(n);
  a.order.resize(n);
  {
    std::size_t i = 0, j = 0, k = 0;
    const auto put = [&](const AgentSnapshot& s, std::uint32_t source) {
      a.px[k] = s.px, a.pz[k] = s.pz, a.vx[k] = s.vx, a.vz[k] = s.vz;
      a.pref_vx[k] = s.pref_vx, a.pref_vz[k] = s.pref_vz, a.radius[k] = s.radius, a.max_speed[k] = s.max_speed;
      a.tether_dx[k] = s.tether_dx, a.tether_dz[k] = s.tether_dz, a.tether_reach[k] = s.tether_reach;
      a.holds[k] = s.holds != 0.0f ? 1u : 0u;
      a.order[k++] = source;
    };
    while (i < a.mine.size() || j < a.ghosts.size()) {
      if (j == a.ghosts.size() || (i < a.mine.size() && a.mine[i].walker <= a.ghosts[j].walker)) {
        if (j < a.ghosts.size() && a.mine[i].walker == a.ghosts[j].walker) ++j;  // kept here too: ours wins
        put(a.mine[i], static_cast<std::uint32_t>(i));
        ++i;
      } else {
        put(a.ghosts[j++], kGhostRow);
      }
    }
    for (auto* v : {&a.px, &a.pz, &a.vx, &a.vz, &a.pref_vx, &a.pref_vz, &a.radius, &a.max_speed, &a.new_vx, &a.new_vz,
                  &a.tether_dx, &a.tether_dz, &a.tether_reach})
      v->resize(k);
    a.order.resize(k);
  }
  const auto start = std::chrono::steady_clock::now();
  AvoidanceJob job;
  job.px = a.px;
  job.pz = a.pz;
  job.vx = a.vx;
  job.vz = a.vz;
  job.pref_vx = a.pref_vx;
  job.pref_vz = a.pref_vz;
  job.radius = a.radius;
  job.max_speed = a.max_speed;
  job.new_vx = a.new_vx;
  job.new_vz = a.new_vz;
  job.tether_dx = a.tether_dx;
  job.tether_dz = a.tether_dz;
  job.tether_reach = a.tether_reach;
  job.holds = a.holds;
  job.obstacles = a.obstacles && !a.obstacles->empty() ? a.obstacles.get() : nullptr;
  job.params = a.avoidance;
  job.params.dt = dt > 0.0f ? dt : a.avoidance.dt;
  job.scratch = &a.scratch;
  run_or_throw(job, "avoidance");
  a.last_avoidance_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  for (std::size_t k = 0; k < a.order.size(); ++k) {
    if (a.order[k] == kGhostRow) continue;
    const CrowdAgents::Row& row = a.rows[a.order[k]];
    SoaTable& t = crowd.world.table(crowd.tables[row.table]);
    t.f32(kWalkerAgent, kAgentOrcaVx)[row.row] = a.new_vx[k];
    t.f32(kWalkerAgent, kAgentOrcaVz)[row.row] = a.new_vz[k];
    // A held agent's answer is no velocity: nonzero, it is where to make way (AvoidanceParameters::make_way).
    std::uint32_t& flags = t.u32(kWalkerAgentState, kAgentFlags)[row.row];
    if (a.holds[k] != 0 && (a.new_vx[k] != 0.0f || a.new_vz[k] != 0.0f))
      flags |= kAgentMakeWay;
    else
      flags &= ~kAgentMakeWay;
  }
  for_each_agent_table(crowd, [&](SoaTable& t, std::uint32_t) {
    run_or_throw(make_agent_move_job(t, dt, a.move), "agent_move");
  });
}

bool all_agents_arrived(const Crowd& crowd) {
  if (!crowd.agents) return false;
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    const SoaTable& t = crowd.world.table(crowd.tables[s]);
    for (std::size_t r = 0; r < t.size(); ++r)
      if ((t.u32(kWalkerAgentState, kAgentFlags)[r] & kAgentArrived) == 0u) return false;
  }
  return true;
}

}  // namespace strata
