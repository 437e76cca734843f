// The procedural default body: budgets, closed 2-manifold skin, outward orientation, plausible size and volume,
// the 53 parts, symmetry and determinism. The body is generated once per test binary (default_body()).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <thread>
#include <vector>

#include <glm/geometric.hpp>
#include <tbb/global_control.h>

#include "io/mesh_check.h"
#include "components/mesh.h"
#include "io/hanim_loader.h"
#include "rig/body_generator.h"
#include "tests/sanitizer_scale.h"

using namespace strata;

namespace {

const Mesh& level(int l) { return l < 3 ? default_body().levels[static_cast<std::size_t>(l)] : default_body().cage; }

// Independent of the generator's own check: edge -> triangle incidences, then each vertex's fan walked as a cycle.
std::string manifold_problem(const Mesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> next;  // (v, a) -> b for triangle (v, a, b)
  std::vector<int> valence(m.vertex_count(), 0);
  for (std::size_t t = 0; t < m.triangles.size(); t += 3)
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = m.triangles[t + c], a = m.triangles[t + (c + 1) % 3], b = m.triangles[t + (c + 2) % 3];
      if (++directed[{v, a}] != 1) return "directed edge used twice";
      next[{v, a}] = b;
      ++valence[v];
    }
  for (const auto& [e, n] : directed)
    if (!directed.count({e.second, e.first})) return "edge without an opposite twin (hole)";
  std::vector<std::uint32_t> first(m.vertex_count(), 0);
  for (const auto& [e, b] : next) first[e.first] = e.second;
  for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
    if (valence[v] == 0) return "unreferenced vertex";
    std::uint32_t a = first[v];
    int steps = 0;
    do {
      a = next.at({v, a});
      ++steps;
    } while (a != first[v] && steps <= valence[v]);
    if (steps != valence[v]) return "vertex fan is not one disc";
  }
  return "";
}

double volume(const Mesh& m) {
  double v = 0.0;
  for (std::size_t t = 0; t < m.triangles.size(); t += 3) {
    const glm::dvec3 a = m.positions[m.triangles[t]], b = m.positions[m.triangles[t + 1]],
                     c = m.positions[m.triangles[t + 2]];
    v += glm::dot(a, glm::cross(b, c)) / 6.0;
  }
  return v;
}

}  // namespace

TEST(Body, VertexBudgetsWithinTwoPercent) {
  const double targets[3] = {17953, 8923, 5133};
  for (int l = 0; l < 3; ++l) {
    EXPECT_NEAR(static_cast<double>(level(l).vertex_count()), targets[l], 0.02 * targets[l]) << "level " << l;
    EXPECT_EQ(level(l).name, "default_body_L" + std::to_string(l));
  }
  EXPECT_GE(level(3).vertex_count(), 1000u);
  EXPECT_LE(level(3).vertex_count(), 2500u);
}

TEST(Body, EveryLevelIsAClosedTwoManifoldWithValidData) {
  for (int l = 0; l < 4; ++l) {
    const Mesh& m = level(l);
    EXPECT_EQ(manifold_problem(m), "") << m.name;
    EXPECT_NO_THROW(validate_mesh(m, m.name));
    EXPECT_EQ(m.normals.size(), m.vertex_count());
    double min_area = 1e30;
    for (std::size_t t = 0; t < m.triangles.size(); t += 3) {
      const glm::dvec3 a = m.positions[m.triangles[t]], b = m.positions[m.triangles[t + 1]],
                       c = m.positions[m.triangles[t + 2]];
      min_area = std::min(min_area, 0.5 * glm::length(glm::cross(b - a, c - a)));
    }
    EXPECT_GT(min_area, 1e-10) << m.name;
  }
}

TEST(Body, OutwardFacingWithAnAdultVolume) {
  for (int l = 0; l < 4; ++l) {
    const double v = volume(level(l));
    EXPECT_GT(v, 0.05) << level(l).name;  // negative would mean inward-facing triangles
    EXPECT_LT(v, 0.09) << level(l).name;
  }
  // Normals point away from the body: at the top of the head up, at the sole down.
  const Mesh& m = level(0);
  const auto top = std::max_element(m.positions.begin(), m.positions.end(),
                                    [](glm::vec3 a, glm::vec3 b) { return a.y < b.y; });
  EXPECT_GT(m.normals[static_cast<std::size_t>(top - m.positions.begin())].y, 0.9f);
}

TEST(Body, StandsOnTheFloorAtAdultHeight) {
  for (int l = 0; l < 3; ++l) {
    float lo = 1e9f, hi = -1e9f;
    for (const glm::vec3& p : level(l).positions) {
      lo = std::min(lo, p.y);
      hi = std::max(hi, p.y);
    }
    EXPECT_NEAR(hi, 1.75f, 0.02f * 1.75f) << level(l).name;
    EXPECT_NEAR(lo, 0.0f, 0.005f) << level(l).name;
  }
}

TEST(Body, AllFiftyThreePartsPresentOnEveryLevel) {
  ASSERT_EQ(paper_part_names().size(), 53u);
  for (int l = 0; l < 3; ++l) {
    const Mesh& m = level(l);
    ASSERT_EQ(m.part_names, paper_part_names());
    std::vector<int> count(m.part_names.size(), 0);
    for (std::uint16_t p : m.part) ++count[p];
    for (std::size_t i = 0; i < count.size(); ++i) EXPECT_GT(count[i], 0) << m.name << " " << m.part_names[i];
  }
}

TEST(Body, PartsSitWhereTheyBelong) {
  const Mesh& m = level(0);
  auto index = [&](const char* name) {
    return static_cast<std::uint16_t>(std::find(m.part_names.begin(), m.part_names.end(), name) -
                                      m.part_names.begin());
  };
  for (std::size_t v = 0; v < m.vertex_count(); ++v) {
    const glm::vec3 p = m.positions[v];
    const std::string& name = m.part_names[m.part[v]];
    if (name[0] == 'l' && name != "lEye") { EXPECT_GT(p.x, 0.0f) << name; }  // +X is the figure's left
    if (name[0] == 'r' && name != "rEye") { EXPECT_LT(p.x, 0.0f) << name; }
    if (m.part[v] == index("head")) { EXPECT_GT(p.y, 1.45f); }
    if (m.part[v] == index("lFoot") || m.part[v] == index("lToe")) { EXPECT_LT(p.y, 0.16f); }
    if (m.part[v] == index("lMid3")) { EXPECT_LT(p.y, 0.76f); }
  }
}

TEST(Body, LeftRightMirrorSymmetric) {
  const Mesh& m = level(0);
  // Bucketed nearest-vertex search for each mirrored vertex.
  const float cell = 0.02f;
  std::map<std::tuple<int, int, int>, std::vector<std::uint32_t>> buckets;
  auto key = [&](glm::vec3 p) {
    return std::make_tuple(int(std::floor(p.x / cell)), int(std::floor(p.y / cell)), int(std::floor(p.z / cell)));
  };
  for (std::uint32_t v = 0; v < m.vertex_count(); ++v) buckets[key(m.positions[v])].push_back(v);
  std::vector<float> miss;
  for (const glm::vec3& p : m.positions) {
    const glm::vec3 q(-p.x, p.y, p.z);
    const auto [i, j, k] = key(q);
    float best = 1e9f;
    for (int di = -1; di <= 1; ++di)
      for (int dj = -1; dj <= 1; ++dj)
        for (int dk = -1; dk <= 1; ++dk) {
          const auto it = buckets.find({i + di, j + dj, k + dk});
          if (it == buckets.end()) continue;
          for (std::uint32_t w : it->second) best = std::min(best, glm::length(m.positions[w] - q));
        }
    miss.push_back(best);
  }
  // The simplifier is not symmetric, so mirrored vertices land between vertices on the other side: compare with
  // the edge length (~1 cm at L0), and let the 99th percentile catch a misplaced limb (~5 % of the skin).
  std::sort(miss.begin(), miss.end());
  EXPECT_LT(miss[miss.size() * 99 / 100], 0.010f);
  EXPECT_LT(miss.back(), 0.025f);
}

// Bit-identical output whatever the thread count: generated again on one worker and compared with default_body()
// (generated on all of them, or read from the cache an earlier process wrote). Under the sanitizers, where the full
// body takes a minute, both sides are a coarser body (twice the grid cell, smaller budgets) generated on one worker
// and on all: the same route through the generator at an eighth of the cells (tests/sanitizer_scale.h).
TEST(Body, DeterministicGenerationWhateverTheThreadCount) {
  const Skeleton skeleton = load_default_humanoid().skeleton;
  BodyOptions options;
  if (test::kSanitizedBuild) {
    options.grid_cell *= 2.0f;
    options.level_vertices = {6000, 3000, 1500};
    options.cage_vertices = 600;
  }
  const auto generate_on = [&](std::size_t workers) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, workers);
    return generate_default_body(skeleton, options);
  };
  const BodyLevels one_worker = generate_on(1);
  const BodyLevels all_workers = test::kSanitizedBuild ? generate_on(std::max(2u, std::thread::hardware_concurrency()))
                                                       : default_body();
  for (int l = 0; l < 4; ++l) {
    const Mesh& a = l < 3 ? all_workers.levels[static_cast<std::size_t>(l)] : all_workers.cage;
    const Mesh& b = l < 3 ? one_worker.levels[static_cast<std::size_t>(l)] : one_worker.cage;
    ASSERT_GT(a.vertex_count(), 0u) << a.name;
    EXPECT_EQ(a.positions, b.positions) << a.name;
    EXPECT_EQ(a.triangles, b.triangles) << a.name;
    EXPECT_EQ(a.part, b.part) << a.name;
  }
}

TEST(Body, MissingJointIsReported) {
  Skeleton sk = load_default_humanoid().skeleton;
  sk.joint_names[static_cast<std::size_t>(sk.find_joint("l_knee"))] = "renamed";
  sk.source_joint_names[static_cast<std::size_t>(sk.find_joint("renamed"))] = "renamed";
  EXPECT_THROW(generate_default_body(sk), std::runtime_error);
}
