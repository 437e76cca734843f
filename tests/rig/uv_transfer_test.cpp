// Texture coordinates carried onto a remeshed surface (rig/uv_transfer.h): exact where the map is linear, clamped
// at seams rather than spanning the texture, and on the shipped MakeHuman body close to MakeHuman's own layout
// (orientation, stretch, seam length) at every level.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <vector>

#include <glm/geometric.hpp>

#include "io/makehuman_pack.h"
#include "rig/makehuman_body.h"
#include "rig/uv_transfer.h"

namespace strata {
namespace {

// An n x n grid of squares over [0, 1]^2 at z = 0, each split along one diagonal or the other.
Mesh grid(int n, bool other_diagonal) {
  Mesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) m.positions.emplace_back(float(x) / n, float(y) / n, 0.0f);
  auto at = [&](int x, int y) { return static_cast<std::uint32_t>(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      if (other_diagonal)
        m.triangles.insert(m.triangles.end(), {at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)});
      else
        m.triangles.insert(m.triangles.end(), {at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y), at(x + 1, y + 1), at(x, y + 1)});
    }
  return m;
}

TEST(UvTransfer, ALinearMapComesThroughExactlyOnAnotherTriangulation) {
  const Mesh source = grid(7, false);
  std::vector<glm::vec2> uvs;
  for (const std::uint32_t v : source.triangles)
    uvs.emplace_back(0.25f + 0.5f * source.positions[v].x, 0.1f + 0.3f * source.positions[v].y + 0.2f * source.positions[v].x);
  const Mesh target = grid(11, true);
  const std::vector<glm::vec2> out = transfer_corner_uvs({source.positions, source.triangles, uvs}, target);
  ASSERT_EQ(out.size(), target.triangles.size());
  for (std::size_t c = 0; c < out.size(); ++c) {
    const glm::vec3 p = target.positions[target.triangles[c]];
    EXPECT_NEAR(out[c].x, 0.25f + 0.5f * p.x, 1e-6f) << c;
    EXPECT_NEAR(out[c].y, 0.1f + 0.3f * p.y + 0.2f * p.x, 1e-6f) << c;
  }
}

// A seam down the middle of the grid (x = 0.5: the left half's texture on the left of the image, the right half's
// far away on the right): every target corner keeps to the side its triangle's centre is on, so no target triangle
// spans the gap between the two islands, although the nearest source point of a corner on the seam line could be
// on either side.
TEST(UvTransfer, ACornerAcrossASeamIsClampedToItsTrianglesSide) {
  const Mesh source = grid(8, false);
  std::vector<glm::vec2> uvs;
  for (std::size_t c = 0; c < source.triangles.size(); ++c) {
    const std::size_t t = c / 3;
    glm::vec3 centre(0.0f);
    for (int k = 0; k < 3; ++k) centre += source.positions[source.triangles[3 * t + k]] / 3.0f;
    const glm::vec3 p = source.positions[source.triangles[c]];
    uvs.emplace_back(centre.x < 0.5f ? 0.5f * p.x : 0.5f + 0.5f * p.x + 0.25f, p.y);  // right island shifted by 0.25
  }
  const Mesh target = grid(5, true);  // its columns straddle x = 0.5
  const std::vector<glm::vec2> out = transfer_corner_uvs({source.positions, source.triangles, uvs}, target);
  for (std::size_t t = 0; t < target.triangles.size() / 3; ++t) {
    float lo = 1e9f, hi = -1e9f;
    for (int k = 0; k < 3; ++k) lo = std::min(lo, out[3 * t + k].x), hi = std::max(hi, out[3 * t + k].x);
    EXPECT_LT(hi - lo, 0.2f) << "triangle " << t << " spans the gap between the islands (u " << lo << " .. " << hi << ")";
  }
}

// A target off the source's surface, even far off, gets the UVs of the source's nearest points (the grid search
// falls back to scanning every triangle rather than growing its cube without end), and a NaN position no NaN.
TEST(UvTransfer, FarAndNonFiniteTargetsStillGetTheNearestUvs) {
  const Mesh source = grid(4, false);
  std::vector<glm::vec2> uvs;
  for (const std::uint32_t v : source.triangles) uvs.emplace_back(source.positions[v].x, source.positions[v].y);
  Mesh target = grid(2, true);
  for (glm::vec3& p : target.positions) p += glm::vec3(0.0f, 0.0f, 500.0f);  // 500 m above the plane
  target.positions[0] = glm::vec3(-300.0f, 0.25f, 0.0f);                     // beyond the source's left edge
  const std::vector<glm::vec2> out = transfer_corner_uvs({source.positions, source.triangles, uvs}, target);
  for (std::size_t c = 0; c < out.size(); ++c) {
    const glm::vec3 p = target.positions[target.triangles[c]];
    EXPECT_NEAR(out[c].x, std::clamp(p.x, 0.0f, 1.0f), 1e-5f) << c;
    EXPECT_NEAR(out[c].y, std::clamp(p.y, 0.0f, 1.0f), 1e-5f) << c;
  }
  target.positions[4].x = std::numeric_limits<float>::quiet_NaN();
  for (const glm::vec2& uv : transfer_corner_uvs({source.positions, source.triangles, uvs}, target))
    EXPECT_TRUE(std::isfinite(uv.x) && std::isfinite(uv.y));
}

TEST(UvTransfer, BadSourceIsAnError) {
  const Mesh m = grid(2, false);
  const std::vector<glm::vec2> short_uvs(m.triangles.size() - 1);
  EXPECT_THROW(transfer_corner_uvs({m.positions, m.triangles, short_uvs}, m), std::invalid_argument);
  EXPECT_THROW(transfer_corner_uvs({m.positions, {}, {}}, m), std::invalid_argument);
  std::vector<std::uint32_t> bad = m.triangles;
  bad[4] = 99;
  const std::vector<glm::vec2> uvs(bad.size());
  EXPECT_THROW(transfer_corner_uvs({m.positions, bad, uvs}, m), std::invalid_argument);
}

double uv_area(const std::vector<glm::vec2>& uv, std::size_t t) {
  const glm::vec2 a = uv[3 * t], b = uv[3 * t + 1], c = uv[3 * t + 2];
  return 0.5 * double((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}
double area(const std::vector<glm::vec3>& p, const std::vector<std::uint32_t>& tri, std::size_t t) {
  return 0.5 * double(glm::length(glm::cross(p[tri[3 * t + 1]] - p[tri[3 * t]], p[tri[3 * t + 2]] - p[tri[3 * t]])));
}

// Edges whose two triangles give a shared vertex different texture coordinates, as a share of all edges.
double seam_share(const std::vector<std::uint32_t>& tri, const std::vector<glm::vec2>& uv) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::size_t> first;  // directed edge -> its corner
  for (std::size_t c = 0; c < tri.size(); ++c) first[{tri[c], tri[c % 3 == 2 ? c - 2 : c + 1]}] = c;
  std::size_t edges = 0, seams = 0;
  for (std::size_t c = 0; c < tri.size(); ++c) {
    const std::size_t next = c % 3 == 2 ? c - 2 : c + 1;
    if (tri[c] > tri[next]) continue;  // each undirected edge once, from its lower end
    const auto it = first.find({tri[next], tri[c]});
    if (it == first.end()) continue;
    const std::size_t o = it->second, onext = o % 3 == 2 ? o - 2 : o + 1;  // o holds tri[next], onext tri[c]
    ++edges;
    seams += glm::length(uv[c] - uv[onext]) > 1e-6f || glm::length(uv[next] - uv[o]) > 1e-6f;
  }
  return edges ? double(seams) / double(edges) : 0.0;
}

// The shipped body against its source: MakeHuman's layout carried onto each level keeps (nearly) every triangle's
// orientation in texture space, scales texture area with surface area as the source does, opens seams only where
// the source has them (a comparable share of edges), and stays in the unit square.
TEST(UvTransfer, TheShippedBodyCarriesMakeHumansLayoutToEveryLevel) {
  const MakeHumanSource source = shipped_makehuman_source();
  ASSERT_EQ(source.corner_uvs.size(), source.triangles.size());
  // The source's texture area per square metre (its surface as packed: the ratio is scale-free enough for
  // orientation and spread, and the levels are compared with the source's own distribution of it).
  std::vector<double> source_density;
  std::size_t source_positive = 0;
  for (std::size_t t = 0; t < source.triangles.size() / 3; ++t) {
    const double a = area(source.positions, source.triangles, t), u = uv_area(source.corner_uvs, t);
    if (a > 0.0) source_density.push_back(std::abs(u) / a);
    source_positive += u > 0.0;
  }
  std::sort(source_density.begin(), source_density.end());
  const double source_median = source_density[source_density.size() / 2];
  const bool counter_clockwise = source_positive * 2 > source.triangles.size() / 3;
  const double source_seams = seam_share(source.triangles, source.corner_uvs);
  RecordProperty("source_seam_share", std::to_string(source_seams));
  const BodyLevels& body = makehuman_default_body();
  for (int l = 0; l < 3; ++l) {
    const Mesh& m = body.levels[static_cast<std::size_t>(l)];
    SCOPED_TRACE("level " + std::to_string(l));
    ASSERT_EQ(m.corner_uvs.size(), m.triangles.size());
    std::size_t flipped = 0;
    std::vector<double> density;
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const double u = uv_area(m.corner_uvs, t);
      flipped += counter_clockwise ? u < 0.0 : u > 0.0;
      const double a = area(m.positions, m.triangles, t);
      if (a > 0.0) density.push_back(std::abs(u) / a);
    }
    for (const glm::vec2& uv : m.corner_uvs) ASSERT_TRUE(uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f && uv.y <= 1.0f);
    std::sort(density.begin(), density.end());
    // The fitted body is the source moved, scaled to 1.75 m and stretched along the limbs: texture per area
    // differs from the source's by that scale, about uniformly.
    const double median = density[density.size() / 2];
    EXPECT_LT(double(flipped), 0.01 * double(m.triangle_count())) << flipped << " triangles turned over in texture space";
    const double spread = density[density.size() * 95 / 100] / density[density.size() * 5 / 100];
    const double source_spread = source_density[source_density.size() * 95 / 100] / source_density[source_density.size() * 5 / 100];
    EXPECT_LT(spread, 2.0 * source_spread) << "texture stretch spread (95th over 5th percentile)";
    EXPECT_GT(median, 0.3 * source_median);
    EXPECT_LT(median, 3.0 * source_median);
    const double seams = seam_share(m.triangles, m.corner_uvs);
    EXPECT_GT(seams, 0.0) << "MakeHuman's layout has seams; so must the levels'";
    EXPECT_LT(seams, 3.0 * source_seams + 0.01);
    std::printf("level %d: flipped %zu of %zu, density median %.3g (source %.3g), spread %.2f (source %.2f), seam share %.4f (source %.4f)\n",
                l, flipped, m.triangle_count(), median, source_median, spread, source_spread, seams, source_seams);
  }
}

}  // namespace
}  // namespace strata
