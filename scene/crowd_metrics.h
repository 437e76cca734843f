#pragma once
// Crowd metrics: an observer run after each step of a scenario crowd (scene/crowd_agents.h) that measures how
// the agents behaved — overlaps between bodies, the closest two ever came, who reached their goal and how long it
// took, who got stuck, and any non-finite agent state. `strata report crowd` and the scenario tests read it; the
// walk's own quality (foot slide) is systems/gait_metrics.h's.
#include <cstdint>
#include <span>
#include <vector>

namespace strata {

struct Crowd;

struct CrowdMetricsReport {
  std::size_t agents = 0;
  std::size_t frames = 0;
  double seconds = 0;
  // Pairs of agents closer than the sum of their radii minus the tolerance, counted over all frames (a pair
  // overlapping for ten frames counts ten).
  std::uint64_t overlaps = 0;
  double min_clearance_m = 0;  // smallest distance minus the radii seen (negative: an overlap)
  double reached_goal_pct = 0; // agents that reached their goal (their first, for cycling goals)
  // Seconds from the first observed step to an agent's first arrival, over the agents that arrived (observe from
  // the crowd's first step for times from spawn).
  double time_to_goal_mean_s = 0, time_to_goal_p95_s = 0;
  std::size_t stuck_agents = 0;  // agents that went stuck_seconds without progress before reaching their goal
  std::uint64_t nan_count = 0;   // non-finite agent values seen
};

// One agent as the metrics read it after a step: what `observe` takes from each of a crowd's agents, so that a
// crowd spread over processes can send its agents' to one observer (apps/report_crowd.cpp).
struct AgentObservation {
  std::uint32_t walker = 0;  // entity index
  float x = 0, z = 0, radius = 0;
  float since_progress = 0;  // s without progress towards the goal
  std::uint32_t arrived = 0;  // 1 once it has reached its goal
  std::uint32_t nonfinite = 0;  // its agent values that are not finite
};
// The agents `crowd` holds (its walker tables; not the remote table), appended to `out` in table order.
void collect_agent_observations(const Crowd& crowd, std::vector<AgentObservation>& out);

class CrowdMetrics {
 public:
  explicit CrowdMetrics(double overlap_tolerance_m = 0.01, double stuck_seconds = 5.0)
      : tolerance_(overlap_tolerance_m), stuck_seconds_(stuck_seconds) {}
  // Call once after each step(crowd, dt). Agents are told apart by their walker's entity index.
  void observe(const Crowd& crowd, float dt);
  // The same from every agent's observation (any order: the figures do not depend on it).
  void observe(std::span<const AgentObservation> agents, float dt);
  CrowdMetricsReport report() const;

 private:
  struct AgentTrack {
    bool seen = false, arrived = false, stuck = false;
    float time_to_goal = 0;
  };
  double tolerance_, stuck_seconds_;
  CrowdMetricsReport report_;
  std::vector<AgentTrack> tracks_;
  bool any_clearance_ = false;
  // Scratch: the crowd's observations, and the neighbour grid's.
  std::vector<AgentObservation> observed_;
  std::vector<float> x_, z_, r_;
  std::vector<std::uint32_t> cell_start_, cell_items_;
};

}  // namespace strata
