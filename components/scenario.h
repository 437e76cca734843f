#pragma once
// A crowd scenario: the ground, the static obstacles, who spawns where, where each group goes, and the agents'
// parameters. Pure data; loaded from the JSON format of docs/scenarios.md by io/scenario_file.h, shipped in
// data/scenarios/ (circle, crossing, bottleneck, plaza, track). Coordinates are metres on the ground plane: x
// and z of the world (y up), written as 2-D points (x, z).
#include <cstdint>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

namespace strata {

// A closed polygon on the ground (x, z), at least 3 points, simple (no self-intersection), counter-clockwise in
// the (x, z) plane read as a 2-D (x, y) plane: its signed area, sum of x_i z_(i+1) - x_(i+1) z_i, is positive (the
// convention of 2-D geometry code such as ORCA's obstacle edges). Note that with y up, seen from above (+Y) with
// +x to the right, +z points down the screen, so such a polygon looks clockwise there. The loader turns boxes
// into polygons and reorders input of the other orientation.
struct ScenarioPolygon {
  std::vector<glm::vec2> points;
};

// Where a spawn group's agents go.
enum class GoalKind : std::uint8_t {
  Point,      // every agent to `points[0]`
  Region,     // each agent to a seeded random point inside the rectangle [region_min, region_max]
  Opposite,   // each agent to its spawn point mirrored through `points[0]` (the circle scenario)
  Waypoints,  // each agent cycles through `points` in order, for ever (starting at the nearest)
  Random,     // continuous random goals: on arrival a new seeded random walkable point inside the ground
};

struct ScenarioGoal {
  GoalKind kind = GoalKind::Point;
  std::vector<glm::vec2> points;  // Point: 1; Opposite: 1 (the centre); Waypoints: >= 2; others: empty
  glm::vec2 region_min{0.0f}, region_max{0.0f};  // Region
  float arrive_radius = 0.5f;  // an agent within this distance of its goal has reached it (m, > 0)
};

enum class SpawnShape : std::uint8_t {
  Circle,  // `count` agents evenly on the circle (center, radius), the first at angle 0 (+x)
  Rect,    // `count` agents on a jittered grid filling [min, max], no two closer than two agent radii
};

struct SpawnGroup {
  std::string name;  // optional; reports and errors name it
  SpawnShape shape = SpawnShape::Rect;
  glm::vec2 center{0.0f};
  float radius = 0.0f;                     // Circle
  glm::vec2 min{0.0f}, max{0.0f};          // Rect
  std::uint32_t count = 0;
  ScenarioGoal goal;
};

// Agent parameters, the same for every group (per-agent variety is drawn from the distributions with the seed).
struct AgentParameters {
  float radius = 0.25f;                     // m, > 0: the disc ORCA keeps apart
  float speed_mean = 1.3f, speed_sd = 0.15f;  // preferred walking speed, m/s: normal, clamped to [min, max]
  float speed_min = 0.8f, speed_max = 1.8f;
  float height_mean = 1.72f, height_sd = 0.07f;  // body height, m (normal, clamped to +- 3 sd)
};

// The stadium track of the original walk (motion/track.h): when present the scenario is the lane walk and has no
// agents, goals or obstacles.
struct TrackLayout {
  std::uint32_t walkers = 25;
  float straight = 5.0f, radius = 2.5f, lane_spacing = 0.9f;
  float speed_min = 1.0f, speed_max = 1.4f;
};

struct Scenario {
  std::string name;
  std::string source;  // file it was loaded from, or "data/scenarios/NAME.json" for a shipped one
  glm::vec2 ground_min{-10.0f}, ground_max{10.0f};  // the walkable rectangle, x and z
  std::vector<ScenarioPolygon> obstacles;           // static, not walkable
  // Optional walkable mesh (an OBJ file, y up, metres) used instead of the ground rectangle for navigation; the
  // obstacles are still cut out of it. Resolved relative to the scenario file.
  std::string walkable_obj;
  std::vector<SpawnGroup> groups;
  AgentParameters agents;
  bool has_track = false;
  TrackLayout track;
  float duration_s = 60.0f;  // how long `report crowd` runs it by default (s, > 0)
  std::uint64_t seed = 1;
  std::size_t agent_count() const {
    std::size_t n = 0;
    for (const SpawnGroup& g : groups) n += g.count;
    return n;
  }
};

}  // namespace strata
