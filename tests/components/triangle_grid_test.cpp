// Nearest-point queries against a triangle soup (components/triangle_grid.h): the grid's answer is brute force's,
// wherever the query lies (inside, far outside, on a tie), and bad input is refused.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <glm/geometric.hpp>

#include "components/triangle_grid.h"

namespace strata {
namespace {

TEST(TriangleGrid, NearestIsBruteForcesAnswerInsideAndFarOutside) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-1.0f, 1.0f), jitter(-0.05f, 0.05f);
  std::vector<glm::vec3> p;
  std::vector<std::uint32_t> tri;
  for (std::uint32_t t = 0; t < 300; ++t) {
    const glm::vec3 centre(coord(rng), coord(rng), coord(rng));
    for (int k = 0; k < 3; ++k) p.push_back(centre + glm::vec3(jitter(rng), jitter(rng), jitter(rng)));
    tri.insert(tri.end(), {3 * t, 3 * t + 1, 3 * t + 2});
  }
  const TriangleGrid grid(p, tri, 0.07f);
  std::uniform_real_distribution<float> wide(-40.0f, 40.0f);
  for (int i = 0; i < 400; ++i) {
    const glm::dvec3 q = i < 200 ? glm::dvec3(coord(rng), coord(rng), coord(rng)) : glm::dvec3(wide(rng), wide(rng), wide(rng));
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < tri.size() / 3; ++t) {
      const glm::dvec3 a(p[tri[3 * t]]), b(p[tri[3 * t + 1]]), c(p[tri[3 * t + 2]]);
      const glm::dvec3 w = closest_barycentric(q, a, b, c);
      best = std::min(best, glm::length(q - (w.x * a + w.y * b + w.z * c)));
    }
    const TriangleGrid::Hit hit = grid.nearest(q);
    ASSERT_NEAR(hit.distance, best, 1e-12) << "query " << i;
    EXPECT_NEAR(hit.barycentric.x + hit.barycentric.y + hit.barycentric.z, 1.0, 1e-12);
  }
}

TEST(TriangleGrid, TiesGoToTheLowerTriangleAndBadInputIsRefused) {
  // The same triangle twice: a tie everywhere, answered by the first.
  const std::vector<glm::vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<std::uint32_t> twice = {0, 1, 2, 0, 1, 2};
  const TriangleGrid grid(p, twice, 0.3f);
  const TriangleGrid::Hit hit = grid.nearest({0.2, 0.2, 0.5});
  EXPECT_EQ(hit.triangle, 0u);
  EXPECT_NEAR(hit.distance, 0.5, 1e-12);
  EXPECT_NEAR(hit.barycentric.y, 0.2, 1e-12);
  EXPECT_NEAR(hit.barycentric.z, 0.2, 1e-12);
  EXPECT_FALSE(std::isfinite(grid.nearest({std::nan(""), 0.0, 0.0}).distance)) << "a NaN query finds nothing";
  EXPECT_THROW(TriangleGrid({}, {}, 0.1f), std::invalid_argument);
  EXPECT_THROW(TriangleGrid(p, std::vector<std::uint32_t>{0, 1, 3}, 0.1f), std::invalid_argument);
  EXPECT_THROW(TriangleGrid(p, twice, 0.0f), std::invalid_argument);
}

}  // namespace
}  // namespace strata
