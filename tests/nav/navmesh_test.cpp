// Global navigation (nav/navmesh.h): paths go around walls and straight over open ground, an unreachable goal
// gives an incomplete path ending near it, starts off the mesh snap, bottleneck's door passes a normal agent and
// stops a wide one, the disk cache round-trips and rebuilds a corrupt file, and queries agree across threads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "io/scenario_file.h"
#include "nav/navmesh.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

ScenarioPolygon box(glm::vec2 lo, glm::vec2 hi) { return {{lo, {hi.x, lo.y}, hi, {lo.x, hi.y}}}; }

// A 20 x 20 m ground with a wall across the middle (x = 0, z from -6 to 10): the way from west to east is round
// its southern end.
Scenario wall_scenario() {
  Scenario s;
  s.name = "wall";
  s.ground_min = glm::vec2(-10.0f);
  s.ground_max = glm::vec2(10.0f);
  s.obstacles.push_back(box({-0.2f, -6.0f}, {0.2f, 10.0f}));
  return s;
}

NavBuildSettings settings(float radius = 0.3f) {
  NavBuildSettings s;
  s.agent_radius = radius;
  return s;
}

float length(const glm::vec2 from, const NavPath& p) {
  float l = 0.0f;
  glm::vec2 a = from;
  for (const glm::vec2& c : p.corners) {
    l += std::hypot(c.x - a.x, c.y - a.y);
    a = c;
  }
  return l;
}

TEST(NavMesh, PathGoesAroundAWall) {
  const auto mesh = NavMesh::build(wall_scenario(), settings(), false);
  EXPECT_FALSE(mesh->info().from_cache);
  EXPECT_GT(mesh->info().polygons, 0u);
  NavQuery q(*mesh);
  const glm::vec2 from(-5.0f, 5.0f), to(5.0f, 5.0f);
  const NavPath p = q.find_path(from, to, 32);
  ASSERT_TRUE(p.complete);
  ASSERT_GE(p.corners.size(), 2u);  // at least one corner round the wall's end, then the goal
  EXPECT_NEAR(p.corners.back().x, to.x, 1e-3f);
  EXPECT_NEAR(p.corners.back().y, to.y, 1e-3f);
  EXPECT_GT(length(from, p), 10.0f + 1.0f);  // the straight line is 10 m; round the end is ~2 x 12 m
  glm::vec2 a = from;
  for (const glm::vec2& c : p.corners) {
    const glm::vec2 mid = 0.5f * (a + c);
    const auto on = q.nearest_walkable(mid, 0.05f);
    ASSERT_TRUE(on.has_value()) << mid.x << ", " << mid.y;
    EXPECT_LT(std::hypot(on->x - mid.x, on->y - mid.y), 0.05f);
    EXPECT_TRUE(q.walkable_line(a, c)) << a.x << "," << a.y << " -> " << c.x << "," << c.y;
    EXPECT_LT(c.y, 10.0f);
    a = c;
  }
  // The corner passes the wall's end (z = -6) at least the agent radius clear of it.
  bool rounds = false;
  for (const glm::vec2& c : p.corners) rounds = rounds || (c.y < -6.0f - 0.25f && std::fabs(c.x) < 1.0f);
  EXPECT_TRUE(rounds);
  EXPECT_FALSE(q.walkable_line(from, to));
  // Inside the wall is not walkable; beside it (beyond the radius) is.
  EXPECT_FALSE(q.nearest_walkable({0.0f, 0.0f}, 0.25f).has_value());
  EXPECT_TRUE(q.nearest_walkable({0.9f, 0.0f}, 0.05f).has_value());
}

TEST(NavMesh, OpenGroundPathIsStraight) {
  Scenario s;
  s.name = "open";
  const auto mesh = NavMesh::build(s, settings(), false);
  NavQuery q(*mesh);
  const NavPath p = q.find_path({-8.0f, -7.0f}, {7.0f, 8.0f});
  ASSERT_TRUE(p.complete);
  ASSERT_EQ(p.corners.size(), 1u);
  EXPECT_NEAR(p.corners[0].x, 7.0f, 1e-3f);
  EXPECT_NEAR(p.corners[0].y, 8.0f, 1e-3f);
  EXPECT_TRUE(q.walkable_line({-8.0f, -7.0f}, {7.0f, 8.0f}));
  // Tiled (4 x 4 tiles of 64 cells), across the seams and through tile corners: still one corner, and the
  // tiled mesh answers like the single tile.
  NavBuildSettings tiled = settings();
  tiled.tile_size = 64;
  const auto tiles = NavMesh::build(s, tiled, false);
  NavQuery tq(*tiles);
  for (const glm::vec2 from : {glm::vec2(-8.0f, -7.0f), glm::vec2(-9.0f, -9.0f), glm::vec2(3.0f, -9.0f)}) {
    const NavPath t = tq.find_path(from, -from, 8);
    EXPECT_TRUE(t.complete);
    EXPECT_EQ(t.corners.size(), 1u) << from.x << ", " << from.y;
  }
  EXPECT_GT(tiles->polygons().size(), mesh->polygons().size());
  // The ground's edge is eroded by the radius.
  EXPECT_FALSE(q.nearest_walkable({-10.0f, 0.0f}, 0.2f).has_value());
  EXPECT_TRUE(q.nearest_walkable({-9.3f, 0.0f}, 0.05f).has_value());
}

TEST(NavMesh, UnreachableGoalGivesAnIncompletePathEndingNearIt) {
  // A closed room of thin walls (3 x 3 m inside) in the middle: its inside is walkable but cut off.
  Scenario s;
  s.name = "closed";
  s.ground_min = glm::vec2(-10.0f);
  s.ground_max = glm::vec2(10.0f);
  s.obstacles = {box({-1.7f, -1.7f}, {1.7f, -1.5f}), box({-1.7f, 1.5f}, {1.7f, 1.7f}),
                 box({-1.7f, -1.5f}, {-1.5f, 1.5f}), box({1.5f, -1.5f}, {1.7f, 1.5f})};
  const auto mesh = NavMesh::build(s, settings(), false);
  NavQuery q(*mesh);
  ASSERT_TRUE(q.nearest_walkable({0.0f, 0.0f}, 0.1f).has_value());  // the inside is mesh, just not connected
  const NavPath p = q.find_path({-8.0f, 0.0f}, {0.0f, 0.0f});
  EXPECT_FALSE(p.complete);
  ASSERT_FALSE(p.corners.empty());
  const glm::vec2 end = p.corners.back();
  EXPECT_LT(std::hypot(end.x, end.y), 1.7f + 0.3f + 0.8f) << end.x << ", " << end.y;  // just outside the wall
  EXPECT_GT(std::max(std::fabs(end.x), std::fabs(end.y)), 1.7f);
}

TEST(NavMesh, StartOffTheMeshSnaps) {
  const auto mesh = NavMesh::build(wall_scenario(), settings(), false);
  NavQuery q(*mesh);
  // Inside the wall, 0.1 m from its west face: snapped out to the walkable side.
  const NavPath p = q.find_path({-0.1f, 5.0f}, {-5.0f, 5.0f});
  ASSERT_TRUE(p.complete);
  ASSERT_FALSE(p.corners.empty());
  EXPECT_NEAR(p.corners.back().x, -5.0f, 1e-3f);
  // Nowhere near the mesh: an empty path.
  const NavPath none = q.find_path({100.0f, 100.0f}, {0.0f, 0.0f});
  EXPECT_TRUE(none.corners.empty());
  EXPECT_FALSE(none.complete);
  const auto snapped = q.nearest_walkable({0.0f, 5.0f}, 1.0f);
  ASSERT_TRUE(snapped.has_value());
  EXPECT_GE(std::fabs(snapped->x), 0.2f + 0.3f - 0.15f);  // eroded by the radius, less voxel and contour error
}

TEST(NavMesh, BottleneckDoorPassesANormalAgentAndStopsAWideOne) {
  const Scenario s = shipped_scenario("bottleneck");
  const glm::vec2 inside(-5.0f, 0.0f), outside(10.0f, 0.0f);
  {
    const auto mesh = NavMesh::build(s, settings(0.3f), false);
    NavQuery q(*mesh);
    const NavPath p = q.find_path(inside, outside, 16);
    EXPECT_TRUE(p.complete);
    ASSERT_FALSE(p.corners.empty());
    EXPECT_NEAR(p.corners.back().x, outside.x, 1e-3f);
  }
  {
    const auto mesh = NavMesh::build(s, settings(0.75f), false);  // wider than the 1.4 m door
    NavQuery q(*mesh);
    const NavPath p = q.find_path(inside, outside, 16);
    EXPECT_FALSE(p.complete);
    if (!p.corners.empty()) {
      EXPECT_LT(p.corners.back().x, 0.0f);  // ends inside the room
    }
  }
}

TEST(NavMesh, CacheRoundTripsAndRebuildsACorruptFile) {
  const test::TempDir tmp("navmesh_test");
  const char* old = std::getenv("XDG_CACHE_HOME");
  const std::string saved = old ? old : "";
  ::setenv("XDG_CACHE_HOME", tmp.path().c_str(), 1);
  const Scenario s = wall_scenario();
  const auto first = NavMesh::build(s, settings(), true);
  EXPECT_FALSE(first->info().from_cache);
  ASSERT_FALSE(first->info().cache_file.empty());
  ASSERT_TRUE(std::filesystem::exists(first->info().cache_file));
  const auto second = NavMesh::build(s, settings(), true);
  EXPECT_TRUE(second->info().from_cache);
  EXPECT_EQ(second->info().build_ms, 0.0);
  EXPECT_EQ(second->polygons(), first->polygons());
  EXPECT_EQ(second->info().polygons, first->info().polygons);
  EXPECT_EQ(second->info().bytes, first->info().bytes);
  // Another radius is another key.
  EXPECT_FALSE(NavMesh::build(s, settings(0.4f), true)->info().from_cache);
  // Flip a byte in the middle: rebuilt, and the rebuilt file is whole again.
  const std::string file = first->info().cache_file;
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(static_cast<std::streamoff>(std::filesystem::file_size(file) / 2));
    char c = 0;
    f.read(&c, 1);
    f.seekp(static_cast<std::streamoff>(std::filesystem::file_size(file) / 2));
    c = static_cast<char>(c ^ 0x5a);
    f.write(&c, 1);
  }
  const auto third = NavMesh::build(s, settings(), true);
  EXPECT_FALSE(third->info().from_cache);
  EXPECT_EQ(third->polygons(), first->polygons());
  // Truncated: rebuilt too.
  std::filesystem::resize_file(file, 20);
  EXPECT_FALSE(NavMesh::build(s, settings(), true)->info().from_cache);
  EXPECT_TRUE(NavMesh::build(s, settings(), true)->info().from_cache);
  if (old)
    ::setenv("XDG_CACHE_HOME", saved.c_str(), 1);
  else
    ::unsetenv("XDG_CACHE_HOME");
}

TEST(NavMesh, QueriesFromTwoThreadsAgree) {
  const auto mesh = NavMesh::build(shipped_scenario("plaza"), settings(), false);
  std::vector<std::pair<glm::vec2, glm::vec2>> pairs;
  std::uint32_t state = 12345;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return static_cast<float>(state >> 8) / static_cast<float>(1u << 24) * 56.0f - 28.0f;
  };
  for (int i = 0; i < 200; ++i) pairs.push_back({{next(), next()}, {next(), next()}});
  std::vector<NavPath> a(pairs.size()), b(pairs.size());
  auto run = [&](std::vector<NavPath>& out) {
    NavQuery q(*mesh);
    for (std::size_t i = 0; i < pairs.size(); ++i) out[i] = q.find_path(pairs[i].first, pairs[i].second, 16);
  };
  std::thread t1(run, std::ref(a)), t2(run, std::ref(b));
  t1.join();
  t2.join();
  std::size_t complete = 0;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    EXPECT_EQ(a[i].complete, b[i].complete);
    EXPECT_EQ(a[i].corners, b[i].corners);
    complete += a[i].complete;
  }
  EXPECT_GT(complete, pairs.size() / 2);  // most random points are off the obstacles
}

TEST(NavMesh, WalkableObjReplacesTheGroundRectangle) {
  // A 12 x 4 m floor at y = 0.5 (two triangles, normals up) in a 40 x 40 m ground rectangle: only the floor is
  // walkable, and an obstacle is still cut out of it.
  const test::TempDir tmp("navmesh_test");
  {
    std::ofstream obj(tmp / "floor.obj");
    obj << "v -6 0.5 -2\nv 6 0.5 -2\nv 6 0.5 2\nv -6 0.5 2\nf 1 3 2\nf 1 4 3\n";
  }
  Scenario s;
  s.name = "floor";
  s.ground_min = glm::vec2(-20.0f);
  s.ground_max = glm::vec2(20.0f);
  s.walkable_obj = (tmp / "floor.obj").string();
  s.obstacles.push_back(box({-0.5f, -2.5f}, {0.5f, 1.0f}));  // leaves a 1 m passage at z in [1, 2]
  const auto mesh = NavMesh::build(s, settings(), false);
  NavQuery q(*mesh);
  EXPECT_FALSE(q.nearest_walkable({0.0f, 10.0f}, 1.0f).has_value());  // in the rectangle, off the floor
  const NavPath p = q.find_path({-5.0f, 0.0f}, {5.0f, 0.0f}, 16);
  ASSERT_TRUE(p.complete);
  bool through_gap = false;
  for (const glm::vec2& c : p.corners) through_gap = through_gap || c.y > 1.0f;
  EXPECT_TRUE(through_gap);
  s.walkable_obj = (tmp / "absent.obj").string();
  EXPECT_THROW((void)NavMesh::build(s, settings(), false), std::runtime_error);
}

TEST(NavMesh, BadSettingsAndEmptyGeometry) {
  NavBuildSettings bad;
  bad.cell_size = 0.0f;
  EXPECT_THROW((void)NavMesh::build(wall_scenario(), bad, false), std::invalid_argument);
  Scenario covered;
  covered.name = "covered";
  covered.ground_min = glm::vec2(-2.0f);
  covered.ground_max = glm::vec2(2.0f);
  covered.obstacles.push_back(box(glm::vec2(-3.0f), glm::vec2(3.0f)));
  try {
    (void)NavMesh::build(covered, settings(), false);
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("covered"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace strata
