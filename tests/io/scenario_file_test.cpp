// The scenario file (io/scenario_file.h): every shipped scenario loads and is sound, and each kind of bad input
// is a one-line LoadError naming the source and the JSON pointer of the element at fault.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <string>

#include "io/load_error.h"
#include "io/scenario_file.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

double signed_area2(const std::vector<glm::vec2>& p) {
  double a = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const glm::vec2 u = p[i], v = p[(i + 1) % p.size()];
    a += static_cast<double>(u.x) * v.y - static_cast<double>(v.x) * u.y;
  }
  return a;
}

bool inside(const std::vector<glm::vec2>& poly, glm::vec2 p) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const glm::vec2 a = poly[i], b = poly[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

// A valid minimal scenario with `extra` spliced in as further top-level keys (or replacing defaults below).
std::string minimal(const std::string& groups = R"([{"count": 4, "spawn": {"shape": "rect", "min": [-5, -5],
    "max": [-3, -3]}, "goal": {"kind": "point", "point": [5, 5]}}])",
                    const std::string& extra = "") {
  return R"({"format": "strata-scenario", "version": 1, "ground": {"min": [-10, -10], "max": [10, 10]},
             "groups": )" +
         groups + extra + "}";
}

// Parses `json` and expects a LoadError whose message names the source and contains `needle`.
void expect_error(const std::string& json, const std::string& needle) {
  SCOPED_TRACE(needle);
  try {
    (void)parse_scenario(json, "bad.json");
    ADD_FAILURE() << "loaded: " << json;
  } catch (const LoadError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind("bad.json: ", 0), 0u) << m;
    EXPECT_NE(m.find(needle), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

TEST(ScenarioFile, EveryShippedScenarioLoadsAndIsSound) {
  const std::vector<std::string> names = shipped_scenario_names();
  EXPECT_EQ(names, (std::vector<std::string>{"bottleneck", "circle", "crossing", "plaza", "track"}));
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    const Scenario s = shipped_scenario(name);
    EXPECT_EQ(s.name, name);
    EXPECT_EQ(s.source, "data/scenarios/" + name + ".json");
    EXPECT_GT(s.duration_s, 0.0f);
    EXPECT_LT(s.ground_min.x, s.ground_max.x);
    EXPECT_LT(s.ground_min.y, s.ground_max.y);
    if (name == "track") {
      EXPECT_TRUE(s.has_track);
      EXPECT_EQ(s.agent_count(), 0u);
      EXPECT_EQ(s.track.walkers, TrackLayout{}.walkers);
      EXPECT_EQ(s.track.straight, TrackLayout{}.straight);
      continue;
    }
    EXPECT_FALSE(s.has_track);
    EXPECT_GT(s.agent_count(), 0u);
    for (const ScenarioPolygon& p : s.obstacles) {
      EXPECT_GE(p.points.size(), 3u);
      EXPECT_GT(signed_area2(p.points), 0.0);
    }
    const float r = s.agents.radius;
    for (const SpawnGroup& g : s.groups) {
      EXPECT_GT(g.count, 0u);
      // Spawn positions: the circle's exactly, the rectangle's corners and centre.
      std::vector<glm::vec2> points;
      if (g.shape == SpawnShape::Circle) {
        for (std::uint32_t i = 0; i < g.count; ++i) {
          const double a = 2.0 * std::numbers::pi * i / g.count;
          points.push_back(g.center + g.radius * glm::vec2(std::cos(a), std::sin(a)));
        }
      } else {
        points = {g.min, g.max, {g.min.x, g.max.y}, {g.max.x, g.min.y}, 0.5f * (g.min + g.max)};
      }
      for (const glm::vec2& p : points) {
        EXPECT_GE(p.x - r, s.ground_min.x);
        EXPECT_GE(p.y - r, s.ground_min.y);
        EXPECT_LE(p.x + r, s.ground_max.x);
        EXPECT_LE(p.y + r, s.ground_max.y);
        for (const ScenarioPolygon& o : s.obstacles) EXPECT_FALSE(inside(o.points, p));
      }
    }
  }
  const Scenario circle = shipped_scenario("circle");
  EXPECT_EQ(circle.agent_count(), 1000u);
  EXPECT_EQ(circle.groups[0].goal.kind, GoalKind::Opposite);
  // Neighbours on the circle at least 2.5 diameters apart.
  EXPECT_GE(2.0 * std::numbers::pi * circle.groups[0].radius / 1000.0, 2.5 * 2.0 * circle.agents.radius);
  EXPECT_EQ(shipped_scenario("plaza").groups[0].goal.kind, GoalKind::Random);
  EXPECT_EQ(shipped_scenario("crossing").groups.size(), 2u);
}

TEST(ScenarioFile, ResolvesNamesAndFiles) {
  EXPECT_EQ(resolve_scenario("bottleneck").name, "bottleneck");
  const test::TempDir tmp("scenario_file_test");
  const std::string path = (tmp / "mine.json").string();
  {
    std::ofstream out(path);
    out << R"({"format": "strata-scenario", "version": 1, "walkable_obj": "floor.obj",
               "groups": [{"count": 1, "spawn": {"shape": "circle", "center": [0, 0], "radius": 1},
                           "goal": {"kind": "opposite", "center": [0, 0]}}]})";
  }
  const Scenario s = resolve_scenario(path);
  EXPECT_EQ(s.name, "mine");
  EXPECT_EQ(s.source, path);
  EXPECT_EQ(s.walkable_obj, (tmp / "floor.obj").string());
  EXPECT_EQ(s.ground_min, glm::vec2(-10.0f));
  try {
    (void)resolve_scenario("no_such_scenario");
    ADD_FAILURE();
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find("circle"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)shipped_scenario("../muscles"), LoadError);
  EXPECT_THROW((void)load_scenario((tmp / "absent.json").string()), LoadError);
}

TEST(ScenarioFile, ClockwisePolygonsBecomeCounterClockwiseAndBoxesPolygons) {
  const Scenario s =
      parse_scenario(minimal(R"([{"count": 1, "spawn": {"shape": "rect", "min": [-9, -9], "max": [-8, -8]},
                   "goal": {"kind": "point", "point": [9, 9]}}])",
                             R"(, "obstacles": [{"polygon": [[0, 0], [0, 2], [2, 2], [2, 0]]},
                                  {"box": {"center": [5, 0], "size": [2, 1], "angle_deg": 90}}])"),
                     "ok.json");
  ASSERT_EQ(s.obstacles.size(), 2u);
  EXPECT_GT(signed_area2(s.obstacles[0].points), 0.0);
  EXPECT_EQ(s.obstacles[0].points.size(), 4u);
  const std::vector<glm::vec2>& box = s.obstacles[1].points;
  ASSERT_EQ(box.size(), 4u);
  EXPECT_NEAR(signed_area2(box), 2.0 * 2.0, 1e-4);  // twice the area of 2 x 1
  // Turned by 90 degrees: 1 m wide in x, 2 m deep in z.
  float lo_x = 1e9f, hi_x = -1e9f, lo_z = 1e9f, hi_z = -1e9f;
  for (const glm::vec2& p : box)
    lo_x = std::min(lo_x, p.x), hi_x = std::max(hi_x, p.x), lo_z = std::min(lo_z, p.y), hi_z = std::max(hi_z, p.y);
  EXPECT_NEAR(hi_x - lo_x, 1.0f, 1e-5f);
  EXPECT_NEAR(hi_z - lo_z, 2.0f, 1e-5f);
  EXPECT_NEAR(0.5f * (lo_x + hi_x), 5.0f, 1e-5f);
}

TEST(ScenarioFile, BadInputNamesTheElement) {
  const std::string group_ok = R"({"count": 4, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                                   "goal": {"kind": "point", "point": [5, 5]}})";
  auto with_group = [](const std::string& g) { return minimal("[" + g + "]"); };
  expect_error("{", "invalid JSON");
  expect_error("[]", "expected an object");
  expect_error(R"({"format": "strata-muscles", "version": 1})", "/format");
  expect_error(R"({"format": "strata-scenario", "version": 2})", "/version");
  expect_error(minimal("[" + group_ok + "]", R"(, "colour": 1)"), "/colour: unknown key");
  expect_error(with_group(R"({"count": 4, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3], "maxx": 1},
                              "goal": {"kind": "point", "point": [5, 5]}})"),
               "/groups/0/spawn/maxx: unknown key");
  expect_error(with_group(R"({"count": "4", "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                              "goal": {"kind": "point", "point": [5, 5]}})"),
               "/groups/0/count: expected an integer");
  expect_error(with_group(R"({"count": 0, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                              "goal": {"kind": "point", "point": [5, 5]}})"),
               "/groups/0/count: must lie in [1, 1000000]");
  expect_error(with_group(R"({"count": 1000001, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                              "goal": {"kind": "point", "point": [5, 5]}})"),
               "/groups/0/count");
  expect_error(with_group(R"({"count": 4, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                              "goal": {"kind": "point"}})"),
               "/groups/0/goal/point: missing");
  expect_error(with_group(R"({"count": 4, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                              "goal": {"kind": "waypoints", "points": [[1, 1]]}})"),
               "/groups/0/goal/points: expected an array of at least 2");
  expect_error(with_group(R"({"count": 4, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                              "goal": {"kind": "region", "min": [1, 1]}})"),
               "/groups/0/goal/max: missing");
  expect_error(with_group(R"({"count": 4, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                              "goal": {"kind": "teleport"}})"),
               "/groups/0/goal/kind");
  expect_error(with_group(R"({"count": 4, "spawn": {"shape": "rect", "min": [-5, -5], "max": [30, -3]},
                              "goal": {"kind": "point", "point": [5, 5]}})"),
               "/groups/0/spawn: the spawn rectangle reaches outside the ground");
  expect_error(with_group(R"({"count": 1000, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                              "goal": {"kind": "point", "point": [5, 5]}})"),
               "/groups/0/spawn: too small");
  expect_error(with_group(R"({"count": 100, "spawn": {"shape": "circle", "center": [0, 0], "radius": 1},
                              "goal": {"kind": "point", "point": [5, 5]}})"),
               "/groups/0/spawn/radius: too small");
  expect_error(with_group(R"({"count": 4, "spawn": {"shape": "hexagon"}, "goal": {"kind": "random"}})"),
               "/groups/0/spawn/shape");
  expect_error(with_group(R"({"count": 4, "spawn": {"shape": "rect", "min": [-5, -5], "max": [-3, -3]},
                              "goal": {"kind": "point", "point": [50, 5]}})"),
               "/groups/0/goal/point: the point reaches outside the ground");
  expect_error(minimal("[]"), "/groups: expected a non-empty array");
  expect_error(minimal("[" + group_ok + "]", R"(, "agents": {"radius": -0.3})"), "/agents/radius");
  expect_error(minimal("[" + group_ok + "]", R"(, "agents": {"speed": {"min": 1.5, "max": 1.0, "mean": 1.2}})"),
               "/agents/speed: min must not exceed max");
  expect_error(minimal("[" + group_ok + "]", R"(, "duration_s": 0)"), "/duration_s");
  expect_error(minimal("[" + group_ok + "]", R"(, "seed": -1)"), "/seed");
  expect_error(minimal("[" + group_ok + "]", R"(, "duration_s": 1e400)"), "invalid JSON");
  expect_error(minimal("[" + group_ok + "]", R"(, "obstacles": [{"polygon": [[0, 0], [1, 0]]}])"),
               "/obstacles/0/polygon: expected an array of at least 3 points");
  expect_error(minimal("[" + group_ok + "]", R"(, "obstacles": [{"polygon": [[0, 0], [2, 2], [2, 0], [0, 2]]}])"),
               "/obstacles/0/polygon: self-intersecting");
  expect_error(minimal("[" + group_ok + "]", R"(, "obstacles": [{"polygon": [[0, 0], [0.0001, 0], [0, 0.0001]]}])"),
               "/obstacles/0/polygon: zero area");
  expect_error(minimal("[" + group_ok + "]", R"(, "obstacles": [{"polygon": [[0, 0], [1, 0], [1, 0], [0, 1]]}])"),
               "/obstacles/0/polygon: points 1 and 2 coincide");
  expect_error(minimal("[" + group_ok + "]", R"(, "obstacles": [{"polygon": [[0, 0], [1, "a"], [0, 1]]}])"),
               "/obstacles/0/polygon/1/1: expected a number");
  expect_error(minimal("[" + group_ok + "]", R"(, "obstacles": [{"box": {"center": [0, 0], "size": [0, 1]}}])"),
               "/obstacles/0/box/size");
  expect_error(minimal("[" + group_ok + "]", R"(, "obstacles": [{"box": {"center": [0, 0]}}])"),
               "/obstacles/0/box/size: missing");
  expect_error(minimal("[" + group_ok + "]", R"(, "obstacles": [{"box": {"center": [0, 0], "size": [1, 1]},
                                                                 "polygon": [[0, 0], [1, 0], [0, 1]]}])"),
               "/obstacles/0: expected exactly one");
  // A spawn rectangle over an obstacle.
  expect_error(minimal("[" + group_ok + "]", R"(, "obstacles": [{"box": {"center": [-4, -4], "size": [0.5, 0.5]}}])"),
               "/groups/0/spawn: overlaps /obstacles/0");
  // Obstacles on a spawn circle: the agent at that angle is named, across the wrap at angle 0 too.
  const std::string ring = R"([{"count": 20, "spawn": {"shape": "circle", "center": [0, 0], "radius": 5},
                                "goal": {"kind": "random"}}])";
  expect_error(minimal(ring, R"(, "obstacles": [{"box": {"center": [0, 5], "size": [0.5, 0.5]}}])"),
               "/groups/0/spawn: overlaps /obstacles/0 (agent 5)");
  expect_error(minimal(ring, R"(, "obstacles": [{"box": {"center": [-5, 0], "size": [0.5, 0.5]}}])"),
               "/groups/0/spawn: overlaps /obstacles/0 (agent 10)");
  expect_error(minimal(ring, R"(, "obstacles": [{"box": {"center": [5.2, 0.05], "size": [0.2, 0.2]}}])"),
               "/groups/0/spawn: overlaps /obstacles/0 (agent 0)");
  EXPECT_NO_THROW((void)parse_scenario(
      minimal(ring, R"(, "obstacles": [{"box": {"center": [0, 0], "size": [4, 4]}}, {"box": {"center": [0, 6],
                                         "size": [1, 0.4]}}])"),
      "ok.json"));
  expect_error(minimal("[" + group_ok + "]", R"(, "ground": {"min": [1, 1], "max": [0, 0]})"), "/ground");
  expect_error(R"({"format": "strata-scenario", "version": 1, "track": {}, "groups": []})",
               "/groups: not allowed with \"track\"");
  expect_error(R"({"format": "strata-scenario", "version": 1, "track": {"speed_min": 2, "speed_max": 1}})",
               "/track: speed_min must not exceed speed_max");
  expect_error(R"({"format": "strata-scenario", "version": 1})", "/groups: missing");
}

// The example in docs/scenarios.md loads, so the documentation cannot drift from the loader unnoticed.
TEST(ScenarioFile, DocumentedExampleLoads) {
  std::ifstream in(std::string(STRATA_TEST_DATA) + "/../../docs/scenarios.md");
  ASSERT_TRUE(in);
  const std::string doc{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::size_t begin = doc.find("```json\n");
  ASSERT_NE(begin, std::string::npos);
  const std::size_t end = doc.find("```", begin + 8);
  const Scenario s = parse_scenario(doc.substr(begin + 8, end - begin - 8), "docs/scenarios.md");
  EXPECT_EQ(s.name, "corridor");
  EXPECT_EQ(s.agent_count(), 80u);
  EXPECT_EQ(s.obstacles.size(), 2u);
  EXPECT_EQ(s.groups[1].goal.kind, GoalKind::Point);
}

}  // namespace
}  // namespace strata
