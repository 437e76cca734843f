#pragma once
// Local avoidance: ORCA, optimal reciprocal collision avoidance (van den Berg, Guy, Lin, Manocha, "Reciprocal
// n-body collision avoidance", ISRR 2011), over SoA agent columns. Each agent takes one half-plane of permitted
// velocities per neighbour (each side taking half the responsibility for avoiding the other) and one per nearby
// static obstacle edge, and picks the permitted velocity nearest its preferred one: a 2-D linear program, with the
// 3-D fallback that minimises the largest violation when the half-planes leave nothing. Neighbours come from a
// uniform spatial grid rebuilt each step. Agents are independent given the last step's positions and velocities,
// so the job runs in oneTBB chunks and gives the same bits for any thread count.
//
//   reads:  position (x, z), velocity, preferred velocity, radius, max speed, the obstacle edges
//   writes: new velocity (x, z)
// Written from the paper; RVO2's source was not used.
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

namespace strata {

struct AvoidanceParameters {
  float time_horizon = 2.0f;           // s: neighbours closer in time than this constrain the velocity
  float obstacle_time_horizon = 0.6f;  // s: the same for static edges
  float neighbor_distance = 4.0f;      // m: neighbours farther than this are not considered
  std::uint32_t max_neighbors = 12;    // nearest ones kept
  float dt = 1.0f / 30.0f;             // s: the step; overlapping agents are pushed apart within one step
};

// Static obstacles as directed edges (a polygon's boundary, counter-clockwise, so the free side is on the right
// of each edge... see avoidance.cpp for the convention), with a grid for the edges near an agent. Built once per
// scenario.
class ObstacleSet {
 public:
  ObstacleSet() = default;
  // Polygons on the ground, counter-clockwise (x, z); throws std::invalid_argument for a polygon under 3 points
  // or a non-finite coordinate.
  explicit ObstacleSet(const std::vector<std::vector<glm::vec2>>& polygons, float cell_size = 2.0f);
  bool empty() const;
  // ...implementation-defined accessors
  struct Edge {
    glm::vec2 a, b;        // from a to b
    glm::vec2 direction;   // unit (b - a)
    bool convex_at_a = true;
    std::uint32_t prev = 0, next = 0;  // neighbouring edges of the same polygon
  };
  const std::vector<Edge>& edges() const { return edges_; }
  // Edges whose grid cells overlap the square of half-size `reach` around p; appended to `out` (sorted, unique).
  void edges_near(glm::vec2 p, float reach, std::vector<std::uint32_t>& out) const;

 private:
  std::vector<Edge> edges_;
  glm::vec2 origin_{0.0f};
  float cell_ = 2.0f;
  std::uint32_t cols_ = 0, rows_ = 0;
  std::vector<std::uint32_t> cell_start_, cell_edges_;
};

// Scratch reused between steps (the neighbour grid); one per crowd.
struct AvoidanceScratch {
  std::vector<std::uint32_t> cell_start, cell_agents;
  // ... whatever the implementation needs, grown never shrunk
};

struct AvoidanceJob {
  // Agent i's columns, all of the same length n.
  std::span<const float> px, pz;          // position (m)
  std::span<const float> vx, vz;          // current velocity (m/s)
  std::span<const float> pref_vx, pref_vz;  // preferred velocity
  std::span<const float> radius;          // m, > 0
  std::span<const float> max_speed;       // m/s, >= 0
  std::span<float> new_vx, new_vz;        // written
  const ObstacleSet* obstacles = nullptr;  // may be null: no static obstacles
  AvoidanceParameters params;
  AvoidanceScratch* scratch = nullptr;

  // Every span the same length, outputs not aliasing inputs, parameters positive and finite, scratch set; inputs
  // finite (a non-finite agent is rejected, not propagated).
  bool validate() const;
  bool run() const;
};

// The scalar twin for tests: the same maths, one agent at a time, neighbours by brute force.
bool run_avoidance_reference(const AvoidanceJob& job);

}  // namespace strata
