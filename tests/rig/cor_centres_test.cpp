// Centres of rotation (rig/cor_centres.h): where they land on a blended tube, independence from the thread
// count, and the disk cache (a stored file comes back, a changed binding or a damaged file recomputes).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <tbb/global_control.h>

#include "rig/body_cache.h"
#include "rig/cor_centres.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

// A tube along x from -0.2 to 0.2 m (radius 5 cm, 16 sides), joint 0 on the left, joint 1 on the right, the
// weights blending linearly over -0.05..0.05 m.
BodyLevel tube() {
  BodyLevel b;
  constexpr int kSides = 16, kRings = 21;
  for (int r = 0; r < kRings; ++r) {
    const float x = -0.2f + 0.4f * static_cast<float>(r) / (kRings - 1);
    for (int s = 0; s < kSides; ++s) {
      const float a = 6.2831853f * static_cast<float>(s) / kSides;
      b.mesh.positions.push_back({x, 0.05f * std::cos(a), 0.05f * std::sin(a)});
      const float w1 = std::clamp((x + 0.05f) / 0.1f, 0.0f, 1.0f);
      b.binding.joints.push_back({0, 1, 0, 0});
      b.binding.weights.push_back({1.0f - w1, w1, 0.0f, 0.0f});
    }
  }
  for (int r = 0; r + 1 < kRings; ++r)
    for (int s = 0; s < kSides; ++s) {
      const auto v = [&](int rr, int ss) { return static_cast<std::uint32_t>(rr * kSides + (ss % kSides)); };
      b.mesh.triangles.insert(b.mesh.triangles.end(), {v(r, s), v(r + 1, s), v(r + 1, s + 1)});
      b.mesh.triangles.insert(b.mesh.triangles.end(), {v(r, s), v(r + 1, s + 1), v(r, s + 1)});
    }
  compute_normals(b.mesh);
  return b;
}

TEST(CorCentres, BlendedVerticesTurnAboutTheAxisNearTheirRing) {
  const BodyLevel b = tube();
  const CorCentres c = compute_cor_centres(b.mesh, b.binding, CorOptions{0.1});  // the paper's width
  std::size_t blended = 0;
  for (std::size_t v = 0; v < b.mesh.vertex_count(); ++v) {
    const glm::vec3 p = b.mesh.positions[v], q = c.centres[v];
    if (b.binding.influence_count(v) < 2) {
      EXPECT_EQ(q, p) << "one influence: no centre needed, the rest position is kept";
      continue;
    }
    ++blended;
    // By symmetry the similar triangles surround the axis: the centre is on it, at about the vertex's ring.
    EXPECT_LT(std::hypot(q.y, q.z), 1e-3f) << v;
    EXPECT_LT(std::abs(q.x - p.x), 0.03f) << v;
  }
  EXPECT_EQ(c.solved, blended);
  EXPECT_EQ(c.fallback, 0u);
  EXPECT_GT(blended, 0u);
}

// A wider similarity averages a ring's centre over more of the blend, weighted towards its middle (the weight
// products peak at w = 0.5, here x = 0): every blended ring's centre moves towards x = 0, never past it, and the
// widths are keyed apart in the cache.
TEST(CorCentres, WiderSimilarityDrawsCentresTowardsTheBlendsMiddle) {
  const BodyLevel b = tube();
  const CorCentres narrow = compute_cor_centres(b.mesh, b.binding, CorOptions{0.1});
  const CorCentres wide = compute_cor_centres(b.mesh, b.binding, CorOptions{0.5});
  std::size_t moved = 0;
  for (std::size_t v = 0; v < b.mesh.vertex_count(); ++v) {
    if (b.binding.influence_count(v) < 2) continue;
    const float x = b.mesh.positions[v].x, n = narrow.centres[v].x, w = wide.centres[v].x;
    EXPECT_LE(std::abs(w), std::abs(n) + 1e-6f) << v;
    EXPECT_GE(w * x, -1e-6f) << v << ": the centre stays on its ring's side of the middle";
    EXPECT_LT(std::hypot(wide.centres[v].y, wide.centres[v].z), 1e-3f) << v;
    moved += std::abs(n) - std::abs(w) > 1e-3f;
  }
  EXPECT_GT(moved, 0u);
  EXPECT_NE(cor_cache_key(b.mesh, b.binding, CorOptions{0.1}), cor_cache_key(b.mesh, b.binding, CorOptions{0.5}));
}

TEST(CorCentres, SameBytesForOneAndTwoThreads) {
  const BodyLevel b = tube();
  std::vector<glm::vec3> result[2];
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    result[threads - 1] = compute_cor_centres(b.mesh, b.binding).centres;
  }
  EXPECT_TRUE(result[0] == result[1]);
}

TEST(CorCentres, DiskCacheKeyedByTheBindingAndRefusingDamagedFiles) {
  const test::TempDir tmp("strata_cor_cache");
  const test::ScopedBodyCacheDir cache(tmp.path());

  BodyLevel b = tube();
  const CorCentres first = cached_cor_centres(b.mesh, b.binding);
  EXPECT_FALSE(first.from_cache);
  const CorCentres second = cached_cor_centres(b.mesh, b.binding);
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(second.centres, first.centres);
  EXPECT_EQ(second.solved, first.solved);

  // An edited weight is another key: recomputed, not served stale.
  b.binding.weights[170] = {0.3f, 0.7f, 0.0f, 0.0f};
  EXPECT_NE(cor_cache_key(b.mesh, b.binding), cor_cache_key(tube().mesh, tube().binding));
  EXPECT_FALSE(cached_cor_centres(b.mesh, b.binding).from_cache);

  // A truncated file is ignored (and the result recomputed).
  const std::uint64_t key = cor_cache_key(b.mesh, b.binding);
  fs::path file;
  for (const auto& e : fs::directory_iterator(tmp.path() / "strata"))
    if (e.path().filename().string().find("cor-") == 0 &&
        load_cor_cache(e.path(), key).has_value())
      file = e.path();
  ASSERT_FALSE(file.empty());
  fs::resize_file(file, fs::file_size(file) / 2);
  EXPECT_FALSE(load_cor_cache(file, key).has_value());
  EXPECT_FALSE(load_cor_cache(file, key + 1).has_value());
  EXPECT_FALSE(cached_cor_centres(b.mesh, b.binding).from_cache);

}

}  // namespace
}  // namespace strata
