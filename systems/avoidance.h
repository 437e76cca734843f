#pragma once
// Local avoidance: ORCA, optimal reciprocal collision avoidance (van den Berg, Guy, Lin, Manocha, "Reciprocal
// n-body collision avoidance", ISRR 2011), over SoA agent columns. Each agent takes one half-plane of permitted
// velocities per neighbour (each side taking half the responsibility for avoiding the other) and one per nearby
// static obstacle edge, and picks the permitted velocity nearest its preferred one: a 2-D linear program. When the
// half-planes leave nothing (dense jams), the paper's 3-D fallback: obstacle and tether half-planes stay hard, and the largest
// violation of the others is minimised, each weighted by 1 / gap to that neighbour; among the velocities achieving
// that minimum, the one nearest the preferred; those agents are then solved once more against their neighbours'
// first answers (AvoidanceParameters::second_pass). Neighbours come from a uniform spatial grid rebuilt each step.
// Within a pass agents are independent (given the last step's state, and in the second pass the first's output),
// so the job runs in oneTBB chunks and gives the same bits for any thread count.
//
// Known limits (tests/systems/avoidance_test.cpp): in that fallback pairs can press a few centimetres into each
// other (a 128-agent antipodal circle: 4.1 cm at 0.6 m radii sum, in 32 steps of the run; 1,000 agents on a 120 m
// ring: 5.3 cm, in 166 of 9,356 steps); an agent sent straight at the middle of an obstacle's face stops there (a
// local method has no side to prefer; routing is navigation's job).
// Written from the paper; RVO2's source was not used.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/vec2.hpp>

namespace strata {

// Fixed capacities of the per-agent linear program, so run() keeps its half-planes on the stack and never
// allocates. validate() refuses max_neighbors above kAvoidanceMaxNeighbors; an agent with more obstacle edges in
// reach than kAvoidanceMaxObstacleEdges keeps the nearest ones (ties by edge index).
inline constexpr std::uint32_t kAvoidanceMaxNeighbors = 64;
inline constexpr std::uint32_t kAvoidanceMaxObstacleEdges = 32;

// Bounds validate() holds the inputs to, far beyond any crowd, so that every intermediate (relative positions
// over a time step, squared distances) stays finite in float.
inline constexpr float kAvoidanceMaxCoordinate = 1.0e6f;  // m
inline constexpr float kAvoidanceMaxSpeed = 1.0e4f;       // m/s, for velocities, preferred velocities, max speed
inline constexpr float kAvoidanceMaxRadius = 1.0e3f;      // m

struct AvoidanceParameters {
  float time_horizon = 2.0f;           // s: neighbours closer in time than this constrain the velocity
  float obstacle_time_horizon = 0.6f;  // s: the same for static edges
  float neighbor_distance = 4.0f;      // m: neighbours farther than this (centre to centre) are not considered
  std::uint32_t max_neighbors = 12;    // nearest ones kept (ties by index), at most kAvoidanceMaxNeighbors
  float dt = 1.0f / 30.0f;             // s: the step; overlapping agents are pushed apart within one step
  // Agents whose half-planes leave nothing get a second solve against their neighbours' first answers (fewer and
  // shallower overlaps in jams; ~13 % more work on the benchmark's crowd, none where every agent finds a velocity).
  bool second_pass = true;
  // Right of way, 0..0.5: between two agents heading the same way (preferred velocities within 60 deg), the one
  // ahead along their common direction takes less of the avoidance and the one behind more, 0.5 -+ right_of_way
  // at a distance of their radii' sum or more along it (linear in between; side by side, half each). The two
  // shares still add up to 1, so ORCA's guarantee holds. 0 is the paper's half each. People queueing at a door
  // follow the one in front; with halves the front agents at a door's mouth hesitated as much as those behind
  // (the bottleneck's door passed ~0.5 agents a second, its queue standing still for 20-30 s at a time).
  float right_of_way = 0.0f;
  // The right of way fades out as the one ahead moves back along their common way (its current velocity), gone
  // at this speed (m/s; 0: never fades). Backed into, the one behind then takes half as with halves instead of
  // retreating for both: with the right of way kept whatever the one ahead did, a push at a door's mouth ran back
  // undamped along a queue (a file of agents walked backwards at 0.3-0.6 m/s against their wish along the wall
  // of a 0.25 m radius bottleneck room, into its corner, where the last pair overlapped by 3 cm: 2 of 12 seeds;
  // with a 0.2 m/s fade, none of those 12). The shares still add up to 1.
  float right_of_way_back_fade = 0.0f;
  // Making way: an agent held still (AvoidanceJob::holds: standing at its goal) that a walking neighbour presses
  // against, blocked (moving at under half its preferred speed, wishing within 60 deg of straight at it, closer
  // than 15 cm gap), gets as its velocity the unit direction off that neighbour's way (across its wish, on the
  // side it already stands; the nearest such neighbour), else 0. The avoidance never moves a held agent itself:
  // navigation reads the direction and moves the agent's standing spot (SteeringParameters::make_way_step). Off:
  // held agents get 0, the paper's static obstacle; standing bodies then never step aside, and a crowd arriving
  // among them walls itself out (the bottleneck's last agents pressed for minutes against those who had stopped).
  bool make_way = false;
  // Passing side, pedestrians' convention of keeping to one side (right in most of the world): an agent meeting
  // others head-on (preferred velocities over 120 deg apart, the other ahead within neighbor_distance and less than
  // the radii's sum plus passing_margin to either side of its way) aims its preferred velocity off to its right by
  // up to passing_angle rad (negative: to its left), fully with passing_full_gap or less between the bodies and
  // fading to nothing at neighbor_distance. The half-planes are untouched, so ORCA's guarantee is too; the turn
  // only moves the velocity the agent would most like among those they permit. Where many meet from all sides,
  // everyone bearing the same way turns the jam into a roundabout (the circle of 1,000: 541 agents stuck -> 133;
  // three 500-agent circles 191 -> 127 on average). A lone pair is not steered by it: their half-planes commit to
  // a side as soon as they come within range. Rejected: forcing the agreed side into the half-plane of a head-on
  // pair when it cost at most 0.15-0.4 m/s more change: lone pairs then kept right, but the 1,000-agent circle had
  // 483 stuck with it alone, 255 with the turn too, and up to twice the frames with a leg out of reach (sharp
  // sidesteps); a 1.5 m margin (75 stuck in the 500-agent circles) made the plaza's walkers swerve for people well
  // off their line (40 -> 65 stuck, 34 -> 40 s to goal over three seeds). 0: off, the paper's ORCA. validate()
  // refuses |passing_angle| over pi/2 and a negative or non-finite margin or gap.
  float passing_angle = 0.0f;
  float passing_margin = 0.3f;    // m
  float passing_full_gap = 1.0f;  // m between the bodies
  // Backing off: the velocity each agent's half-planes are set about (the paper's v_opt, its current velocity)
  // keeps at most this speed (m/s) against the agent's preferred velocity; negative: off, the paper's. The half-planes
  // are set about the pair's current velocities, so once one of a pair has given way the avoidance left for the
  // other is small: a walker going round the plaza's fountain, met by one coming the other way round, was moved
  // straight back along the wall at up to 1.5-1.7 m/s for a second and more while the other barely slowed. Set about
  // a velocity that backs off no faster than this, the pair shares what is left again. Any v_opt the two agents of a
  // pair agree on keeps ORCA's guarantee (both read the same inputs). Rejected: no backing off at all in v_opt (0
  // with no queue's push passed back: the bottleneck's room stayed jammed, 6-27 % in after 240 s).
  float back_off_limit = -1.0f;
};

// The velocity agent half-planes are set about (AvoidanceParameters::back_off_limit): the current velocity `v`,
// less the part of its speed against the preferred velocity `preferred` beyond `limit` (m/s; negative: v as is).
glm::vec2 back_off_velocity(glm::vec2 v, glm::vec2 preferred, float limit);

// Static obstacles: solid, non-walkable polygons on the ground, kept as directed edges with a grid for the edges
// near an agent. Built once per scenario.
//
// Edge convention: inside ObstacleSet every polygon is oriented so that its interior lies on the LEFT of each edge
// a -> b in the (x, z) plane read as ordinary (x, y) axes (positive shoelace area), i.e. the free side is on the
// right, outward normal (direction.y, -direction.x). A polygon given the other way round is reversed on
// construction, so either winding is accepted. (Beware: "counter-clockwise seen from above" with y up is
// clockwise in (x, z) read as (x, y), because +z points towards the viewer's bottom when looking down -y; the
// signed area, not the caller's word, decides.) Consecutive duplicate points are dropped; collinear points are
// kept as separate edges; a polygon of zero area (all points on one line) is a thin wall with both faces.
class ObstacleSet {
 public:
  ObstacleSet() = default;
  // Polygons on the ground (x, z); throws std::invalid_argument for a polygon under 3 points (after dropping
  // repeated points), a non-finite coordinate or one beyond kAvoidanceMaxCoordinate, or a cell size that is not
  // finite and positive.
  explicit ObstacleSet(const std::vector<std::vector<glm::vec2>>& polygons, float cell_size = 2.0f);
  bool empty() const { return edges_.empty(); }

  struct Edge {
    glm::vec2 a, b;        // from a to b; the polygon's interior is on the left
    glm::vec2 direction;   // unit (b - a)
    float length = 0.0f;   // |b - a| > 0
    bool convex_at_a = true;  // the polygon's corner at a turns left (or goes straight): convex seen from inside
    std::uint32_t prev = 0, next = 0;  // neighbouring edges of the same polygon: prev ends at a, next starts at b
  };
  const std::vector<Edge>& edges() const { return edges_; }

  // Edges whose grid cells overlap the square of half-size `reach` around p; appended to `out` (sorted, unique).
  // For tools and tests; the job uses for_each_edge_near, which allocates nothing.
  void edges_near(glm::vec2 p, float reach, std::vector<std::uint32_t>& out) const;

  // Calls visit(edge index) for every edge registered in a grid cell overlapping the square of half-size `reach`
  // around p. An edge spanning several cells is visited once per cell: callers deduplicate.
  template <class Visit>
  void for_each_edge_near(glm::vec2 p, float reach, Visit&& visit) const {
    if (cols_ == 0) return;
    std::uint32_t x0, x1, z0, z1;
    if (!cell_span(p, reach, x0, x1, z0, z1)) return;
    for (std::uint32_t z = z0; z <= z1; ++z)
      for (std::uint32_t x = x0; x <= x1; ++x) {
        const std::size_t cell = static_cast<std::size_t>(z) * cols_ + x;
        for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) visit(cell_edges_[k]);
      }
  }

 private:
  // The inclusive cell range overlapping the square; false when it misses the grid.
  bool cell_span(glm::vec2 p, float reach, std::uint32_t& x0, std::uint32_t& x1, std::uint32_t& z0,
                 std::uint32_t& z1) const;

  std::vector<Edge> edges_;
  glm::vec2 origin_{0.0f};
  float cell_ = 2.0f;
  std::uint32_t cols_ = 0, rows_ = 0;
  std::vector<std::uint32_t> cell_start_, cell_edges_;  // CSR: cell c's edges are cell_edges_[start[c], start[c+1])
};

// Scratch reused between steps (the neighbour grid, rebuilt by a counting sort each run); one per crowd. Grown,
// never shrunk, so a crowd of steady size allocates only on its first step. run() is the only writer: one job at
// a time per scratch.
struct AvoidanceScratch {
  std::vector<std::uint32_t> cell_start;   // CSR offsets, cells + 1
  std::vector<std::uint32_t> cell_agents;  // agent indices in cell order (stable: ascending index within a cell)
  std::vector<std::uint32_t> agent_cell;   // each agent's cell
  std::vector<float> sorted_x, sorted_z;   // positions in cell order, so a cell's scan reads contiguous memory
  std::vector<std::uint8_t> infeasible;    // per agent: the first pass found no permitted velocity
  std::vector<float> first_vx, first_vz;   // the first pass's velocities, read by the second
  // The first pass's chosen neighbours of each agent it left infeasible (max_neighbors slots per agent, packed
  // (squared distance, index) keys as the search keeps them, and their count): the second pass solves those agents
  // again from the same positions, so it reads them instead of searching the grid again.
  std::vector<std::uint64_t> kept_neighbors;
  std::vector<std::uint32_t> kept_count;
  // And its preferred velocity as the passing side turned it (which reads only this step's inputs), so the second
  // pass neither gathers the neighbours again nor recomputes it.
  std::vector<float> kept_preferred_x, kept_preferred_z;
  // Each agent's back_off_velocity, which every half-plane against it is set about (the first pass).
  std::vector<float> plane_vx, plane_vz;
};

struct AvoidanceJob {
  // Agent i's columns, all of the same length n.
  std::span<const float> px, pz;          // position (m)
  std::span<const float> vx, vz;          // current velocity (m/s)
  std::span<const float> pref_vx, pref_vz;  // preferred velocity
  std::span<const float> radius;          // m, > 0
  std::span<const float> max_speed;       // m/s, >= 0
  std::span<float> new_vx, new_vz;        // written
  // Optional (empty, or all three of length n): a tether per agent. Its next position p + v dt stays within
  // tether_reach of the point p + (tether_dx, tether_dz) whenever a velocity meeting every other half-plane does
  // (otherwise the tether is dropped for this step: it never costs a neighbour its avoidance). Crowds tether an
  // agent to its walking body, which a planted foot may hold back (systems/locomotion.h GaitStyle::lag_dip): an
  // agent that ran on ahead of its feet would leave them dragging. tether_reach <= 0 means no tether.
  std::span<const float> tether_dx, tether_dz, tether_reach;
  // Optional (empty, or length n): agents that will not move this step whatever avoidance answers (non-zero; a
  // walker leaving or settling into its stance waits for its feet, systems/agent_move.h). Their neighbours avoid
  // them wholly, as a still obstacle, instead of counting on them for half; their own answer is zero.
  std::span<const std::uint8_t> holds;
  const ObstacleSet* obstacles = nullptr;  // may be null: no static obstacles
  AvoidanceParameters params;
  AvoidanceScratch* scratch = nullptr;

  // Every span the same length, outputs not aliasing inputs or each other, parameters positive and finite
  // (max_neighbors 1..kAvoidanceMaxNeighbors), scratch set; inputs finite and within the kAvoidanceMax* bounds,
  // radius > 0, max_speed >= 0 (a non-finite agent is rejected, not propagated). No side effects.
  bool validate() const;
  // validate() first; false and nothing written when invalid. Every written velocity is finite and no longer than
  // the agent's max_speed.
  bool run() const;
};

// The scalar twin for tests: the same maths, one agent at a time, neighbours and obstacle edges by brute force,
// serial; ignores `scratch` (may be null). Its output equals run()'s bit for bit.
bool run_avoidance_reference(const AvoidanceJob& job);

}  // namespace strata
