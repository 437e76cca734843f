// Navigation's goal points (systems/navigation.h): where a region goal's points may lie.
#include <gtest/gtest.h>

#include <cstdint>

#include "systems/navigation.h"

namespace strata {
namespace {

ScenarioGoal region(glm::vec2 lo, glm::vec2 hi) {
  ScenarioGoal g;
  g.kind = GoalKind::Region;
  g.region_min = lo;
  g.region_max = hi;
  return g;
}

// The bottleneck's region, 8 m deep along x and 14 m wide, entered from its -x side.
TEST(RegionGoal, PointsKeepOffTheEdgeTheAgentComesInBy) {
  const ScenarioGoal g = region({5.0f, -7.0f}, {13.0f, 7.0f});
  const glm::vec2 from(-5.0f, 1.0f);
  // The drawn point's coordinate along the way is rescaled into [6, 13]; across it, kept as drawn.
  EXPECT_FLOAT_EQ(region_point_past_entrance(g, {5.0f, 3.0f}, from, 1.0f).x, 6.0f);
  EXPECT_FLOAT_EQ(region_point_past_entrance(g, {13.0f, 3.0f}, from, 1.0f).x, 13.0f);
  EXPECT_FLOAT_EQ(region_point_past_entrance(g, {9.0f, 3.0f}, from, 1.0f).x, 9.5f);
  EXPECT_FLOAT_EQ(region_point_past_entrance(g, {9.0f, 3.0f}, from, 1.0f).y, 3.0f);
  // From the far side the band is at the other edge.
  EXPECT_FLOAT_EQ(region_point_past_entrance(g, {13.0f, 0.0f}, {20.0f, 0.0f}, 1.0f).x, 12.0f);
  EXPECT_FLOAT_EQ(region_point_past_entrance(g, {5.0f, 0.0f}, {20.0f, 0.0f}, 1.0f).x, 5.0f);
  // Coming in along z (from the south), z is the coordinate moved.
  const glm::vec2 south = region_point_past_entrance(g, {8.0f, -7.0f}, {9.0f, -30.0f}, 1.0f);
  EXPECT_FLOAT_EQ(south.x, 8.0f);
  EXPECT_FLOAT_EQ(south.y, -6.0f);
}

TEST(RegionGoal, NoBandWhereTheRegionIsTooShallowOrTheGoalIsNoRegion) {
  const glm::vec2 drawn(5.5f, 0.0f);
  // 1.5 m deep: less than twice the margin, so the whole depth stays usable.
  EXPECT_EQ(region_point_past_entrance(region({5.0f, -7.0f}, {6.5f, 7.0f}), drawn, {-5.0f, 0.0f}, 1.0f), drawn);
  EXPECT_EQ(region_point_past_entrance(region({5.0f, -7.0f}, {13.0f, 7.0f}), drawn, {-5.0f, 0.0f}, 0.0f), drawn);
  ScenarioGoal point;
  point.kind = GoalKind::Point;
  point.points = {drawn};
  EXPECT_EQ(region_point_past_entrance(point, drawn, {-5.0f, 0.0f}, 1.0f), drawn);
  // A degenerate region (no depth) is returned as drawn, never NaN.
  const glm::vec2 flat = region_point_past_entrance(region({5.0f, 0.0f}, {5.0f, 0.0f}), {5.0f, 0.0f}, {-5.0f, 0.0f}, 1.0f);
  EXPECT_EQ(flat, glm::vec2(5.0f, 0.0f));
}

TEST(RegionGoal, FirstGoalsFillTheRegionButItsEntranceBand) {
  const ScenarioGoal g = region({5.0f, -7.0f}, {13.0f, 7.0f});
  int in_band[2] = {0, 0};
  float deepest = 0.0f;
  for (std::uint32_t seed = 1; seed <= 2000; ++seed) {
    for (int k = 0; k < 2; ++k) {
      std::uint32_t rng = seed * 2654435761u | 1u, waypoint = 7;
      const glm::vec2 p = first_goal(g, {-5.0f, 0.0f}, {-20.0f, -20.0f}, {20.0f, 20.0f}, rng, waypoint, k == 0 ? 1.0f : 0.0f);
      ASSERT_GE(p.x, 5.0f);
      ASSERT_LE(p.x, 13.0f);
      ASSERT_GE(p.y, -7.0f);
      ASSERT_LE(p.y, 7.0f);
      EXPECT_EQ(waypoint, 0u);
      if (p.x < 6.0f) ++in_band[k];
      if (k == 0) deepest = std::max(deepest, p.x);
    }
  }
  EXPECT_EQ(in_band[0], 0) << "with the margin";
  EXPECT_GT(in_band[1], 150) << "uniform points: about one in eight lies in the first metre";
  EXPECT_GT(deepest, 12.9f) << "the far side is still used";
}

}  // namespace
}  // namespace strata
