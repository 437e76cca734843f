#pragma once
// Crowd metrics: an observer run after each step of a scenario crowd (scene/crowd_agents.h) that measures how
// the agents behaved — overlaps between bodies, the closest two ever came, who reached their goal and how long it
// took, who got stuck, and any non-finite agent state. `strata report crowd` and the scenario tests read it; the
// walk's own quality (foot slide) is systems/gait_metrics.h's.
#include <cstdint>
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

class CrowdMetrics {
 public:
  explicit CrowdMetrics(double overlap_tolerance_m = 0.01, double stuck_seconds = 5.0)
      : tolerance_(overlap_tolerance_m), stuck_seconds_(stuck_seconds) {}
  // Call once after each step(crowd, dt). Agents are told apart by their walker's entity index.
  void observe(const Crowd& crowd, float dt);
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
  // Scratch of the neighbour grid.
  std::vector<float> x_, z_, r_;
  std::vector<std::uint32_t> cell_start_, cell_items_;
};

}  // namespace strata
