#pragma once
// Crowd metrics: an observer run after each step of a scenario crowd (scene/crowd_agents.h) that measures how
// the agents behaved — overlaps between bodies, the closest two ever came, who reached their goal and how long it
// took, who got stuck, and any non-finite agent state. `strata report crowd` and the scenario tests read it; the
// walk's own quality (foot slide) is systems/gait_metrics.h's.
//
// A crowd spread over processes (apps/report_crowd.cpp) observes it piecewise: each process observes the agents
// it owns, with the other processes' agents near its slab as `border` observations (pairs across a border are
// counted once, by the process owning the agent of the lower index), and at the end rank 0 merges every process's
// metrics (pack / merge): the same figures as one observer of the whole crowd, with per-step traffic that grows
// with the borders, not with the crowd. Everything per agent is therefore kept as "first frame when" (an agent's
// first arrival, the first frame it was seen stuck), which merges by taking the earliest.
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
  // Smallest distance minus the radii of any two agents seen (negative: an overlap), among the pairs that came
  // within the observer's pair reach (1 m of clearance by default): the reach when none did.
  double min_clearance_m = 0;
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
  // Pairs are measured when their clearance is under `pair_reach_m` (overlaps and near misses; what lies further
  // apart tells nothing about avoidance).
  explicit CrowdMetrics(double overlap_tolerance_m = 0.01, double stuck_seconds = 5.0, double pair_reach_m = 1.0)
      : tolerance_(overlap_tolerance_m), stuck_seconds_(stuck_seconds), pair_reach_(pair_reach_m) {}
  // Call once after each step(crowd, dt). Agents are told apart by their walker's entity index.
  void observe(const Crowd& crowd, float dt);
  // The same from every agent's observation (any order: the figures do not depend on it).
  void observe(std::span<const AgentObservation> agents, float dt);
  // One process's share of a crowd: the agents it owns, and `border` agents owned elsewhere, which count only in
  // pairs with an owned agent of lower entity index (their owner counts their other pairs and the agents
  // themselves). Every process must observe every step.
  void observe(std::span<const AgentObservation> owned, std::span<const AgentObservation> border, float dt);
  // The clearance under which two agents are measured as a pair: a process needs its neighbours' agents within
  // this plus two agent radii of its slab as `border` observations.
  double pair_reach_m() const { return pair_reach_; }
  CrowdMetricsReport report() const;

  // This observer's figures as bytes, and another observer's (of other agents, over the same steps) merged in:
  // overlaps add up, clearances take the smaller, each agent keeps its earliest arrival and stuck frames. Throws
  // std::runtime_error for malformed bytes (nothing merged) or another number of steps.
  std::vector<std::uint8_t> pack() const;
  void merge(std::span<const std::uint8_t> bytes);

 private:
  static constexpr std::uint32_t kNever = 0xffffffffu;
  struct AgentTrack {
    bool seen = false;
    std::uint32_t arrival_frame = kNever, stuck_frame = kNever;  // first frame (0-based) it arrived, was stuck
    float time_to_goal = 0;                                      // seconds at its arrival frame
  };
  double tolerance_, stuck_seconds_, pair_reach_;
  CrowdMetricsReport report_;
  std::vector<AgentTrack> tracks_;
  bool any_clearance_ = false;
  // Scratch: the crowd's observations, and the neighbour grid's.
  std::vector<AgentObservation> observed_;
  std::vector<float> x_, z_, r_;
  std::vector<std::uint32_t> walker_;
  std::vector<std::uint32_t> cell_start_, cell_items_;
};

}  // namespace strata
