// Baked ambient occlusion (rig/vertex_occlusion.h): an open surface sees the whole sky, an inner corner less of
// it, nothing non-finite comes out of degenerate input, the thread count changes no bit, and the default body is
// darker where it folds than where it is open.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>

#include <tbb/global_control.h>

#include "rig/body_generator.h"
#include "rig/vertex_occlusion.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

// A square grid of `n` x `n` quads in the plane through `origin` spanned by `u` and `v` (metres), facing u x v.
void add_grid(Mesh& m, glm::vec3 origin, glm::vec3 u, glm::vec3 v, int n) {
  const auto base = static_cast<std::uint32_t>(m.positions.size());
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.positions.push_back(origin + u * (static_cast<float>(i) / n) + v * (static_cast<float>(j) / n));
  const auto at = [&](int i, int j) { return base + static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      m.triangles.insert(m.triangles.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1), at(i, j + 1)});
}

TEST(VertexOcclusion, AnOpenPlaneSeesTheWholeSky) {
  Mesh plane;
  add_grid(plane, {-0.5f, 0.0f, 0.5f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -1.0f}, 8);  // faces +Y
  const VertexOcclusion o = bake_vertex_occlusion(plane);
  ASSERT_EQ(o.open.size(), plane.vertex_count());
  for (float a : o.open) EXPECT_FLOAT_EQ(a, 1.0f);
}

// A floor and a wall meeting at z = 0: floor vertices at the wall's foot are occluded by it, those half a metre
// out (twice the range) are not, and occlusion falls off in between.
TEST(VertexOcclusion, AnInnerCornerIsDarkerThanTheOpenFloor) {
  Mesh corner;
  add_grid(corner, {-0.5f, 0.0f, 0.5f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -0.5f}, 20);  // floor z 0.5 .. 0, faces +Y
  add_grid(corner, {-0.5f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.5f, 0.0f}, 20);   // wall, faces +Z
  const VertexOcclusion o = bake_vertex_occlusion(corner);
  auto floor_at = [&](float z) {  // the floor vertex at x = 0 nearest z
    std::size_t best = 0;
    for (std::size_t v = 0; v < 21 * 21; ++v)
      if (std::abs(corner.positions[v].x) < 1e-4f &&
          std::abs(corner.positions[v].z - z) < std::abs(corner.positions[best].z - z) + (std::abs(corner.positions[best].x) > 1e-4f ? 1e9f : 0.0f))
        best = v;
    return o.open[best];
  };
  const float at_wall = floor_at(0.025f), near = floor_at(0.1f), open = floor_at(0.5f);
  EXPECT_LT(at_wall, 0.85f);
  EXPECT_LT(at_wall, near);
  EXPECT_LT(near, open);
  EXPECT_GT(open, 0.99f);
  for (float a : o.open) {
    EXPECT_GE(a, 0.0f);
    EXPECT_LE(a, 1.0f);
  }
}

TEST(VertexOcclusion, DegenerateInputGivesFiniteValues) {
  Mesh m;
  add_grid(m, {-0.5f, 0.0f, 0.5f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -1.0f}, 2);
  m.positions.push_back({0.0f, 0.2f, 0.0f});  // three coincident points: a zero-area triangle
  m.positions.push_back({0.0f, 0.2f, 0.0f});
  m.positions.push_back({0.0f, 0.2f, 0.0f});
  m.positions.push_back({std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f});
  const auto n = static_cast<std::uint32_t>(m.positions.size());
  m.triangles.insert(m.triangles.end(), {n - 4, n - 3, n - 2, n - 1, 0, 1, 0, 1, 99});  // out of range too
  const VertexOcclusion o = bake_vertex_occlusion(m);
  ASSERT_EQ(o.open.size(), m.vertex_count());
  for (float a : o.open) {
    EXPECT_TRUE(std::isfinite(a));
    EXPECT_GE(a, 0.0f);
    EXPECT_LE(a, 1.0f);
  }
}

TEST(VertexOcclusion, SameBitsWhateverTheThreadCount) {
  const Mesh& m = default_body().levels[2];
  const VertexOcclusion all = bake_vertex_occlusion(m);
  VertexOcclusion one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = bake_vertex_occlusion(m);
  }
  ASSERT_EQ(all.open, one.open);
}

// The default body: the crotch (between the thighs, below the hip) is occluded, the top of the head is open.
TEST(VertexOcclusion, TheDefaultBodyIsDarkerWhereItFolds) {
  const Mesh& m = default_body().levels[2];
  const VertexOcclusion o = bake_vertex_occlusion(m);
  std::size_t top = 0;
  float fold = 1.0f;
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    if (m.positions[v].y > m.positions[top].y) top = v;
    const std::string& part = m.part_names[m.part[v]];
    if (part == "lThigh" || part == "rThigh") fold = std::min(fold, o.open[v]);
  }
  EXPECT_GT(o.open[top], 0.9f);
  EXPECT_LT(fold, 0.6f);
  EXPECT_GT(o.seconds, 0.0);
}

// The disk cache: the second request loads the first one's bake; a changed mesh is another key; a damaged file
// is baked again.
TEST(VertexOcclusion, CachedOnDiskBesideTheBody) {
  const test::TempDir tmp("strata_occlusion_cache");
  const test::ScopedBodyCacheDir cache(tmp.path());

  Mesh corner;
  add_grid(corner, {-0.5f, 0.0f, 0.5f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -0.5f}, 8);
  add_grid(corner, {-0.5f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, 0.5f, 0.0f}, 8);
  const VertexOcclusion first = cached_vertex_occlusion(corner);
  EXPECT_FALSE(first.from_cache);
  const VertexOcclusion second = cached_vertex_occlusion(corner);
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(second.open, first.open);
  Mesh moved = corner;
  moved.positions[0].y += 0.01f;
  EXPECT_FALSE(cached_vertex_occlusion(moved).from_cache);
  for (const auto& e : std::filesystem::directory_iterator(tmp.path() / "strata"))
    if (e.path().filename().string().rfind("occlusion-", 0) == 0) std::filesystem::resize_file(e.path(), 20);
  const VertexOcclusion again = cached_vertex_occlusion(corner);
  EXPECT_FALSE(again.from_cache);
  EXPECT_EQ(again.open, first.open);

}

}  // namespace
}  // namespace strata
