// The subdivided cage (rig/subdiv_topology.h, systems/subdiv.h): the per-frame path against OpenSubdiv's own
// refinement, watertightness, no NaN on extreme poses, run-time level switching, open boundaries and
// face-varying UVs.
#include <gtest/gtest.h>

#include "tests/apps/strata_cli_runner.h"
#include "tests/temp_dir.h"
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include <opensubdiv/far/primvarRefiner.h>
#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <tbb/global_control.h>

#include "io/hanim_loader.h"
#include "reference/skin_reference.h"
#include "rig/body_rig.h"
#include "rig/cor_centres.h"
#include "rig/subdiv_refiner.h"
#include "rig/subdiv_topology.h"
#include "systems/animation_sample.h"
#include "systems/fk.h"
#include "scene/crowd.h"
#include "systems/subdiv.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "render/scene_draw.h"
#include "scene/step.h"
#include "tests/systems/job_test_util.h"

namespace strata {
namespace {

namespace Far = OpenSubdiv::Far;

struct Point3 {
  float x = 0, y = 0, z = 0;
  void Clear() { x = y = z = 0.0f; }
  void AddWithWeight(const Point3& s, float w) {
    x += w * s.x;
    y += w * s.y;
    z += w * s.z;
  }
};

Rig default_rig() {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  return rig;
}

// One walker at the origin facing +Z in the rest pose, after one frame at `level`.
std::unique_ptr<Crowd> rest_scene(const Rig& rig, DetailLevel level) {
  auto scene = std::make_unique<Crowd>(rig);
  CrowdConfig config;
  config.motion = MotionSource::Clip;
  config.clip = kRestPose;
  config.walkers = 1;
  config.heading_jitter = 0.0f;
  spawn_crowd(*scene, config);
  set_detail_level(*scene, level);
  Profiler profiler(4, false);
  step(*scene, 1.0f / 30.0f, profiler);
  return scene;
}

// Every directed edge once and its reverse once: closed, 2-manifold along edges, consistently oriented.
void expect_watertight(const std::vector<std::uint32_t>& triangles, const char* what) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (std::size_t t = 0; t < triangles.size(); t += 3)
    for (int k = 0; k < 3; ++k) ++directed[{triangles[t + k], triangles[t + (k + 1) % 3]}];
  std::size_t bad = 0;
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) ++bad;
  }
  EXPECT_EQ(bad, 0u) << what << ": directed edges not matched by exactly one reverse edge";
}

TEST(Subdiv, DefaultBodyCarriesABoundCage) {
  const auto body = default_bound_body();
  ASSERT_EQ(body->levels.size(), 3u) << "the cage is not one of the levels";
  ASSERT_TRUE(body->cage.has_value());
  EXPECT_EQ(body->cage->binding.vertex_count(), body->cage->mesh.vertex_count());
  EXPECT_GT(body->cage->mesh.vertex_count(), 1000u);
  for (std::size_t v = 0; v < body->cage->binding.vertex_count(); ++v) ASSERT_GE(body->cage->binding.influence_count(v), 1);
  // Built once per rig: a second request is the same object.
  EXPECT_EQ(body_subdiv_surface(*body, 2).get(), body_subdiv_surface(*body, 2).get());
}

// The per-frame path (cage skinned at rest, level-by-level stencils from layout order, output order) against
// OpenSubdiv refining the rest cage level by level with PrimvarRefiner::Interpolate, and against its factorised
// stencil table.
TEST(Subdiv, RestCageMatchesOpenSubdivRefinement) {
  const Rig rig = default_rig();
  const Mesh& cage = rig.body->cage->mesh;
  for (int depth = 1; depth <= kMaxSubdivDepth; ++depth) {
    const auto scene = rest_scene(rig, DetailLevel::subdiv(depth));
    ASSERT_NE(scene->skin.subdiv.get(), nullptr);
    const SkinnedCrowd& out = current_skinned(*scene);

    std::unique_ptr<Far::TopologyRefiner> refiner = make_cage_refiner(cage);
    refiner->RefineUniform(Far::TopologyRefiner::UniformOptions(depth));
    const Far::PrimvarRefiner primvar(*refiner);
    std::vector<Point3> level(cage.vertex_count());
    for (std::size_t i = 0; i < level.size(); ++i) level[i] = {cage.positions[i].x, cage.positions[i].y, cage.positions[i].z};
    for (int l = 1; l <= depth; ++l) {
      std::vector<Point3> next(static_cast<std::size_t>(refiner->GetLevel(l).GetNumVertices()));
      primvar.Interpolate(l, level, next);
      level = std::move(next);
    }
    Far::StencilTableFactoryReal<float>::Options options;
    options.generateIntermediateLevels = false;
    std::unique_ptr<const Far::StencilTableReal<float>> table(Far::StencilTableFactoryReal<float>::Create(*refiner, options));
    std::vector<Point3> cage_points(cage.vertex_count()), factorised(static_cast<std::size_t>(table->GetNumStencils()));
    for (std::size_t i = 0; i < cage.vertex_count(); ++i)
      cage_points[i] = {cage.positions[i].x, cage.positions[i].y, cage.positions[i].z};
    table->UpdateValues(cage_points.data(), factorised.data());

    ASSERT_EQ(out.vertex_count, level.size());
    ASSERT_EQ(factorised.size(), level.size());
    float worst = 0.0f, worst_factorised = 0.0f;
    const std::vector<std::uint32_t>& osd = scene->skin.subdiv.get()->opensubdiv_vertex;
    ASSERT_EQ(osd.size(), level.size());
    for (std::size_t i = 0; i < level.size(); ++i) {
      const glm::vec3 p = out.position(0, i);
      const Point3& a = level[osd[i]];
      const Point3& b = factorised[osd[i]];
      worst = std::max(worst, glm::length(p - glm::vec3(a.x, a.y, a.z)));
      worst_factorised = std::max(worst_factorised, glm::length(p - glm::vec3(b.x, b.y, b.z)));
    }
    // The renumbered triangles are OpenSubdiv's faces, in its face order.
    const Far::TopologyLevel& last = refiner->GetLevel(depth);
    ASSERT_EQ(scene->skin.subdiv.get()->triangles.size(), 3u * static_cast<std::size_t>(last.GetNumFaces()));
    for (int f = 0; f < last.GetNumFaces(); ++f)
      for (int k = 0; k < 3; ++k)
        ASSERT_EQ(osd[scene->skin.subdiv.get()->triangles[3 * static_cast<std::size_t>(f) + k]],
                  static_cast<std::uint32_t>(last.GetFaceVertices(f)[k]));
    EXPECT_LT(worst, 1e-5f) << "S" << depth;
    EXPECT_LT(worst_factorised, 1e-5f) << "S" << depth;

    // Normals: the area-weighted average compute_normals (an independent implementation) gives on the same mesh.
    Mesh refined;
    refined.triangles = scene->skin.subdiv.get()->triangles;
    for (std::size_t i = 0; i < out.vertex_count; ++i) refined.positions.push_back(out.position(0, i));
    compute_normals(refined);
    float normal_gap = 0.0f;
    for (std::size_t i = 0; i < out.vertex_count; ++i)
      normal_gap = std::max(normal_gap, glm::length(out.normal(0, i) - refined.normals[i]));
    EXPECT_LT(normal_gap, 1e-4f) << "S" << depth;
  }
}

// S1..S3 in every skinning mode: the refined surface of a walking walker is the stencils applied to the cage as
// the scalar twin skins it (reference/skin_reference.h, the mode's double-precision definition), placed.
TEST(Subdiv, EverySkinningModeRefinesTheTwinsCage) {
  const Rig rig = default_rig();
  const BodyLevel& cage = *rig.body->cage;
  for (const SkinningMode mode : kSkinningModes)
    for (int depth = 1; depth <= kMaxSubdivDepth; ++depth) {
      Crowd scene(rig);
      CrowdConfig config;
      config.motion = MotionSource::Walk;
      config.walkers = 2;
      spawn_crowd(scene, config);
      set_skinning_mode(scene, mode);
      set_detail_level(scene, DetailLevel::subdiv(depth));
      Profiler profiler(4, false);
      for (int f = 0; f < 8; ++f) step(scene, 1.0f / 30.0f, profiler);
      const SubdivSurface& surface = *scene.skin.subdiv;
      const SkinnedCrowd& out = current_skinned(scene);
      const WalkerLanes lanes = scene.lanes();
      const std::vector<glm::vec3> centres = compute_cor_centres(cage.mesh, cage.binding).centres;
      float worst = 0.0f;
      for (std::size_t w = 0; w < lanes.count; ++w) {
        const SkinnedVertices ref =
            skin_reference(cage.mesh, cage.binding, walker_skinning_matrices(lanes, w), mode, centres);
        const Placement P = placement_of(lanes, w);
        const std::size_t n = surface.cage_layout.vertex_count;
        std::vector<float> x(n), y(n), z(n);
        for (std::size_t i = 0; i < n; ++i) {
          const glm::vec3 p = P.point(ref.positions[surface.cage_layout.original[i]]);
          x[i] = p.x, y[i] = p.y, z[i] = p.z;
        }
        for (const SubdivStencils& st : surface.steps) {
          std::vector<float> nx(st.rows()), ny(st.rows()), nz(st.rows());
          apply_subdiv_stencils(st, x.data(), y.data(), z.data(), nx.data(), ny.data(), nz.data());
          x.swap(nx), y.swap(ny), z.swap(nz);
        }
        ASSERT_EQ(x.size(), out.vertex_count);
        for (std::size_t i = 0; i < out.vertex_count; ++i)
          worst = std::max(worst, glm::length(out.position(w, i) - glm::vec3(x[i], y[i], z[i])));
      }
      EXPECT_LT(worst, 1e-5f) << skinning_mode_name(mode) << " S" << depth;
    }
}

TEST(Subdiv, RefinedCageStaysWatertight) {
  const auto body = default_bound_body();
  expect_watertight(body->cage->mesh.triangles, "cage");
  for (int depth = 1; depth <= kMaxSubdivDepth; ++depth) {
    const auto surface = body_subdiv_surface(*body, depth);
    ASSERT_EQ(surface->triangle_count(), body->cage->mesh.triangle_count() << (2 * depth)) << "Loop: 4 per level";
    expect_watertight(surface->triangles, ("S" + std::to_string(depth)).c_str());
    // Same topology as the cage: V - E + F = 2 (closed, sphere-like), E = 3F / 2.
    const auto v = static_cast<long>(surface->vertex_count), f = static_cast<long>(surface->triangle_count());
    EXPECT_EQ(v - 3 * f / 2 + f, 2) << "S" << depth;
    for (std::uint32_t i : surface->triangles) ASSERT_LT(i, surface->vertex_count);
  }
}

// Random large joint rotations, limbs collapsed to a point, a walker scaled to nothing: every output finite,
// every normal unit length.
TEST(Subdiv, NoNanOnExtremePoses) {
  const Rig rig = default_rig();
  Crowd scene(rig);
  CrowdConfig config;
  config.motion = MotionSource::Clip;
  config.clip = kRestPose;
  config.walkers = 6;
  spawn_crowd(scene, config);
  set_detail_level(scene, DetailLevel::subdiv(2));
  Profiler profiler(4, false);
  step(scene, 0.1f, profiler);
  std::mt19937_64 rng(5);
  std::normal_distribution<float> wild(0.0f, 3.0f);
  WalkerLanes lanes = scene.lanes();
  for (std::size_t w = 0; w < lanes.count; ++w)
    for (std::uint32_t j = 0; j < lanes.joints; ++j) {
      const glm::quat q = glm::normalize(glm::quat(wild(rng), wild(rng), wild(rng), wild(rng)));
      const float xyzw[4] = {q.x, q.y, q.z, q.w};
      for (int c = 0; c < 4; ++c) lanes.local_rotation[(j * 4 + c) * lanes.stride + w] = xyzw[c];
    }
  ASSERT_TRUE(make_fk_job(rig.skeleton, scene.table(initial_slot(scene))).run());
  // Walkers 1-2: arms and legs collapsed (zero skinning matrices); walker 3: placement scale 0 (everything at
  // one point, every triangle degenerate).
  for (const char* name : {"l_elbow", "r_elbow", "l_knee", "r_knee", "l_shoulder"}) {
    const int j = rig.skeleton.find_joint(name);
    ASSERT_GE(j, 0) << name;
    for (std::size_t w : {1, 2})
      for (std::uint32_t c = 0; c < kAffineFloats; ++c) lanes.skinning[(j * kAffineFloats + c) * lanes.stride + w] = 0.0f;
  }
  scene.table(initial_slot(scene)).f32(kWalkerPlacement, 4)[3] = 0.0f;
  SkinnedCrowd out;
  ASSERT_TRUE(make_subdiv_job(*scene.skin.subdiv.get(), scene.table(initial_slot(scene)), out).run());
  std::size_t bad = 0, plus_y = 0;
  for (std::size_t w = 0; w < out.walkers; ++w)
    for (std::size_t v = 0; v < out.vertex_count; ++v) {
      const glm::vec3 p = out.position(w, v), n = out.normal(w, v);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !(std::abs(glm::length(n) - 1.0f) < 1e-3f))
        ++bad;
      plus_y += w == 3 && n == glm::vec3(0, 1, 0);
    }
  EXPECT_EQ(bad, 0u);
  EXPECT_EQ(plus_y, out.vertex_count) << "a fully collapsed walker falls back to +Y normals";
}

TEST(Subdiv, LevelSwitchingAtRunTimeChangesWhatIsDrawn) {
  const Rig rig = default_rig();
  Crowd scene(rig);
  CrowdConfig config;
  config.walkers = 3;
  config.motion = MotionSource::Walk;
  spawn_crowd(scene, config);
  Profiler profiler(4, false);
  const std::size_t cage_triangles = rig.body->cage->mesh.triangle_count();
  const DetailLevel order[] = {DetailLevel::mesh(0), DetailLevel::subdiv(2), DetailLevel::mesh(1),
                               DetailLevel::subdiv(1), DetailLevel::subdiv(3), DetailLevel::mesh(2),
                               DetailLevel::subdiv(2), DetailLevel::none()};
  for (DetailLevel level : order) {
    set_detail_level(scene, level);
    step(scene, 1.0f / 30.0f, profiler);
    EXPECT_TRUE(scene.skin.level == level) << level.name();
    if (level.is_none()) {
      EXPECT_EQ(current_skinned(scene).walkers, 0u);
      EXPECT_TRUE(body_draw_inputs(scene).empty());
      continue;
    }
    const auto mesh = static_cast<std::size_t>(level.index());
    const std::size_t expected = level.is_subdiv() ? cage_triangles << (2 * level.index())
                                                   : rig.body->levels[mesh].mesh.triangle_count();
    EXPECT_EQ(current_triangles(scene).size(), 3 * expected) << level.name();
    const std::size_t vertices = level.is_subdiv() ? scene.skin.subdiv.get()->vertex_count
                                                   : rig.body->levels[mesh].mesh.vertex_count();
    EXPECT_EQ(current_skinned(scene).vertex_count, vertices) << level.name();
    EXPECT_EQ(current_skinned(scene).walkers, 3u);
  }
  // A body without a cage draws level 0 when asked for S levels.
  Rig plain = rig;
  plain.body = std::make_shared<const Body>(Body{rig.body->levels});
  Crowd no_cage(plain);
  set_detail_level(no_cage, DetailLevel::subdiv(2));
  EXPECT_EQ(no_cage.skin.level, DetailLevel::mesh(0));
  EXPECT_EQ(no_cage.skin.subdiv.get(), nullptr);
}

TEST(Subdiv, AnyThreadCountGivesTheSameBytes) {
  const Rig rig = default_rig();
  Crowd scene(rig);
  CrowdConfig config;
  config.walkers = 7;
  config.motion = MotionSource::Walk;
  spawn_crowd(scene, config);
  set_detail_level(scene, DetailLevel::subdiv(1));
  Profiler profiler(4, false);
  step(scene, 0.2f, profiler);
  SkinnedCrowd one, many;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    ASSERT_TRUE(make_subdiv_job(*scene.skin.subdiv.get(), scene.table(initial_slot(scene)), one).run());
  }
  ASSERT_TRUE(make_subdiv_job(*scene.skin.subdiv.get(), scene.table(initial_slot(scene)), many).run());
  ASSERT_EQ(one.px.size(), many.px.size());
  EXPECT_EQ(std::memcmp(one.px.data(), many.px.data(), one.px.size() * 4), 0);
  EXPECT_EQ(std::memcmp(one.nz.data(), many.nz.data(), one.nz.size() * 4), 0);
}

// An open, flat, UV-mapped patch (u = x, v = y): the boundary must not shrink (corners fixed, boundary points on
// the boundary lines), and the face-varying UVs, refined once, must follow the refined positions.
TEST(Subdiv, OpenBoundaryKeepsItsEdgeAndUvsAreRefinedOnce) {
  constexpr int kN = 5;  // vertices per side
  BodyLevel patch;
  patch.mesh.name = "patch";
  for (int y = 0; y < kN; ++y)
    for (int x = 0; x < kN; ++x) {
      const glm::vec2 uv{x / float(kN - 1), y / float(kN - 1)};
      patch.mesh.positions.emplace_back(uv.x, uv.y, 0.0f);
      patch.mesh.uvs.push_back(uv);
      patch.mesh.part.push_back(0);
    }
  patch.mesh.part_names = {"hip"};
  for (int y = 0; y + 1 < kN; ++y)
    for (int x = 0; x + 1 < kN; ++x) {
      // Diagonals alternate so each patch corner has one triangle: EDGE_AND_CORNER keeps only such a vertex
      // fixed (a boundary vertex with two faces is smoothed along the boundary like any other).
      const std::uint32_t a = y * kN + x, b = a + 1, c = a + kN, d = c + 1;
      if ((x + y) % 2 == 0)
        for (std::uint32_t i : {a, b, c, b, d, c}) patch.mesh.triangles.push_back(i);
      else
        for (std::uint32_t i : {a, b, d, a, d, c}) patch.mesh.triangles.push_back(i);
    }
  compute_normals(patch.mesh);
  patch.binding.joints.assign(patch.mesh.vertex_count(), {0, 0, 0, 0});
  patch.binding.weights.assign(patch.mesh.vertex_count(), {1.0f, 0.0f, 0.0f, 0.0f});

  for (int depth = 1; depth <= kMaxSubdivDepth; ++depth) {
    const SubdivSurface s = make_subdiv_surface(patch, depth);
    ASSERT_EQ(s.uv_triangles.size(), s.triangles.size());
    ASSERT_FALSE(s.uvs.empty());
    // Positions, refined as the cage's are (identity skinning through the per-frame stencils).
    std::vector<float> x(patch.mesh.vertex_count()), y(x.size()), z(x.size());
    for (std::uint32_t i = 0; i < x.size(); ++i) {
      const std::uint32_t v = s.cage_layout.original[i];
      x[i] = patch.mesh.positions[v].x, y[i] = patch.mesh.positions[v].y, z[i] = patch.mesh.positions[v].z;
    }
    for (const SubdivStencils& step : s.steps) {
      std::vector<float> nx(step.rows()), ny(step.rows()), nz(step.rows());
      apply_subdiv_stencils(step, x.data(), y.data(), z.data(), nx.data(), ny.data(), nz.data());
      x = std::move(nx), y = std::move(ny), z = std::move(nz);
    }
    glm::vec2 lo(1e9f), hi(-1e9f);
    std::size_t on_boundary = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      lo = glm::min(lo, glm::vec2(x[i], y[i]));
      hi = glm::max(hi, glm::vec2(x[i], y[i]));
      EXPECT_NEAR(z[i], 0.0f, 1e-6f);
      on_boundary += std::min({std::abs(x[i]), std::abs(y[i]), std::abs(1 - x[i]), std::abs(1 - y[i])}) < 1e-6f;
    }
    EXPECT_NEAR(lo.x, 0.0f, 1e-6f) << "the boundary did not shrink";
    EXPECT_NEAR(lo.y, 0.0f, 1e-6f);
    EXPECT_NEAR(hi.x, 1.0f, 1e-6f);
    EXPECT_NEAR(hi.y, 1.0f, 1e-6f);
    EXPECT_EQ(on_boundary, static_cast<std::size_t>(4 * (kN - 1) << depth)) << "every boundary point on the boundary";
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
      const glm::vec2 uv = s.uvs[s.uv_triangles[t]];
      const std::uint32_t v = s.triangles[t];
      ASSERT_NEAR(uv.x, x[v], 1e-5f) << "corner " << t;
      ASSERT_NEAR(uv.y, y[v], 1e-5f) << "corner " << t;
    }
  }
}

// The default body's cage carries MakeHuman's texture coordinates per corner (seams included); every subdivision
// level refines them as one face-varying channel, keeping the seams: each refined corner has a UV in the unit
// square, more distinct UVs than vertices, and (nearly) no triangle turned over in texture space.
TEST(Subdiv, TheDefaultBodysSeamedUvsAreRefinedAtEveryLevel) {
  const auto body = default_bound_body();
  ASSERT_TRUE(body->cage);
  ASSERT_EQ(body->cage->mesh.corner_uvs.size(), body->cage->mesh.triangles.size());
  for (int depth = 1; depth <= kMaxSubdivDepth; ++depth) {
    SCOPED_TRACE("S" + std::to_string(depth));
    const SubdivSurface s = make_subdiv_surface(*body->cage, depth);
    ASSERT_EQ(s.uv_triangles.size(), s.triangles.size());
    EXPECT_GT(s.uvs.size(), s.vertex_count) << "the seams split UVs";
    for (const std::uint32_t i : s.uv_triangles) {
      ASSERT_LT(i, s.uvs.size());
      const glm::vec2 uv = s.uvs[i];
      ASSERT_TRUE(uv.x >= 0.0f && uv.x <= 1.0f && uv.y >= 0.0f && uv.y <= 1.0f);
    }
    std::size_t positive = 0;
    for (std::size_t t = 0; t + 2 < s.uv_triangles.size(); t += 3) {
      const glm::vec2 a = s.uvs[s.uv_triangles[t]], b = s.uvs[s.uv_triangles[t + 1]], c = s.uvs[s.uv_triangles[t + 2]];
      positive += (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x) > 0.0f;
    }
    const std::size_t triangles = s.triangles.size() / 3;
    EXPECT_GT(std::max(positive, triangles - positive), triangles * 98 / 100) << positive << " of " << triangles;
  }
}

// validate() rejects each missing or mismatched input, and run() then writes nothing.
TEST(SubdivJob, JobValidity) {
  const Rig rig = default_rig();
  const auto scene = rest_scene(rig, DetailLevel::subdiv(1));
  const SubdivSurface& surface = *scene->skin.subdiv.get();
  const SoaTable& table = scene->table(initial_slot(*scene));
  using namespace test;
  const std::size_t stride = pad_to_lanes(surface.vertex_count);
  std::vector<float> block(6 * stride, kSentinel);
  auto block_untouched = [&] {
    for (float v : block)
      if (v != kSentinel) return false;
    return true;
  };
  const SubdivWalkerJob good = make_subdiv_walker_job(surface, table, 0, skin_output_in(block.data(), stride));
  SubdivWalkerJob j = good;
  j.surface = nullptr;
  expect_refused(j, "no surface", block_untouched);
  j = good, j.walker = 1;
  expect_refused(j, "walker out of range", block_untouched);
  j = good, j.out.capacity = surface.vertex_count - 1;
  expect_refused(j, "output too short for the refined surface", block_untouched);
  j = good, j.skinning = with_count(good.skinning, 0);
  expect_refused(j, "skinning of no walkers", block_untouched);
  j = good, j.placement = without_base(good.placement);
  expect_refused(j, "no placement", block_untouched);
  SubdivSurface broken = surface;
  broken.steps[0].source_count += 1;
  j = good, j.surface = &broken;
  expect_refused(j, "stencils that do not read the cage", block_untouched);
  broken = surface;
  broken.vertex_count += 1;
  j = good, j.surface = &broken;
  expect_refused(j, "stencils that do not end at the surface's vertices", block_untouched);
  EXPECT_TRUE(good.run());
  EXPECT_FALSE(block_untouched());

  SkinnedCrowd crowd;
  const SubdivJob crowd_job = make_subdiv_job(surface, table, crowd);
  for (AlignedBuffer<float>* b : {&crowd.px, &crowd.py, &crowd.pz, &crowd.nx, &crowd.ny, &crowd.nz})
    for (std::size_t i = 0; i < b->size(); ++i) (*b)[i] = kSentinel;
  auto crowd_untouched = [&] {
    for (const AlignedBuffer<float>* b : {&crowd.px, &crowd.py, &crowd.pz, &crowd.nx, &crowd.ny, &crowd.nz})
      for (std::size_t i = 0; i < b->size(); ++i)
        if ((*b)[i] != kSentinel) return false;
    return true;
  };
  SubdivJob c = crowd_job;
  c.out = nullptr;
  expect_refused(c, "no output crowd", crowd_untouched);
  crowd.walkers = 2;
  expect_refused(crowd_job, "crowd prepared for another walker count", crowd_untouched);
  crowd.walkers = 1;
  crowd.vertex_count -= 1;
  expect_refused(crowd_job, "crowd prepared for another surface", crowd_untouched);
  crowd.vertex_count += 1;
  EXPECT_TRUE(crowd_job.run());
  EXPECT_FALSE(crowd_untouched());
}

TEST(Subdiv, RejectsBadInput) {
  const auto body = default_bound_body();
  EXPECT_THROW(make_subdiv_surface(*body->cage, 0), std::invalid_argument);
  EXPECT_THROW(make_subdiv_surface(*body->cage, 4), std::invalid_argument);
  BodyLevel unbound{body->cage->mesh, {}};
  EXPECT_THROW(make_subdiv_surface(unbound, 1), std::invalid_argument);
  EXPECT_THROW(make_subdiv_surface(BodyLevel{}, 1), std::invalid_argument);
}

// ---- The command line: --level S1..S3 in crowd and bench, and `strata report subdiv` ----------------------------

namespace fs = std::filesystem;

using Result = test::CliResult;
Result run(const std::string& args) { return test::run_strata(args); }

// One scratch directory for the test program (CTest runs each test in a program of its own), removed when it exits.
fs::path scratch(const std::string& name) {
  static const test::TempDir dir("strata_subdiv_test");
  fs::path p = dir / name;
  fs::remove_all(p);
  return p;
}

TEST(SubdivCli, CrowdAndBenchDrawTheRefinedCage) {
  const auto body = default_bound_body();
  const fs::path out = scratch("crowd_s2");
  Result r = run("crowd --walkers 2 --frames 2 --width 96 --height 64 --level S2 --no-progress --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.out;
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary.at("body_level_name"), "S2");
  EXPECT_EQ(summary.at("body_vertices"), body_subdiv_surface(*body, 2)->vertex_count);
  bool timed = false;
  for (const auto& system : summary.at("systems")) timed |= system.at("name") == "subdiv";
  EXPECT_TRUE(timed) << summary.at("systems").dump();

  const fs::path json = scratch("bench_s1.json");
  Result b = run("bench --walkers 3 --frames 2 --level s1 --threads 1 --json " + json.string());
  ASSERT_EQ(b.status, 0) << b.out;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(json));
  EXPECT_EQ(j.at("level_name"), "S1");
  EXPECT_EQ(j.at("vertices_per_walker"), body_subdiv_surface(*body, 1)->vertex_count);

  Result bad = run("bench --walkers 1 --frames 1 --level S4");
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.out.find("S3"), std::string::npos) << bad.out;
  const fs::path gltf = fs::path(STRATA_SHARED_DATA) / "gltf_khronos_samples" / "CesiumMan.glb";
  if (fs::exists(gltf)) {
    Result no_cage = run("bench --walkers 1 --frames 1 --level S1 --mesh " + gltf.string());
    EXPECT_NE(no_cage.status, 0);
    EXPECT_NE(no_cage.out.find("subdivision cage"), std::string::npos) << no_cage.out;
  }
}

TEST(SubdivCli, ReportWritesCostsAndDeviation) {
  const fs::path json = scratch("subdiv.json");
  Result r = run("report subdiv --batches 1 --json " + json.string());
  ASSERT_EQ(r.status, 0) << r.out;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(json));
  ASSERT_EQ(j.at("levels").size(), 3u);
  std::size_t previous = 0;
  for (const auto& level : j.at("levels")) {
    for (const char* key : {"refine_ns_per_vertex", "factorised_soa_ns_per_vertex", "far_update_values_ns_per_vertex",
                            "normals_ns_per_vertex", "walker_us"})
      EXPECT_GT(level.at(key).get<double>(), 0.0) << key;
    EXPECT_LT(level.at("forms_max_difference_m").get<double>(), 1e-5) << "our stencils and Far's agree";
    EXPECT_GT(level.at("vertices").get<std::size_t>(), 3 * previous) << "each level about 4x the last";
    previous = level.at("vertices").get<std::size_t>();
  }
  EXPECT_EQ(j.at("routes").size(), 6u) << "levels 0-2 skinned directly, S1-S3 refined";
  // The refined cage and level 0 are two tessellations of one body: close (cm), but not identical.
  const double deviation = j.at("max_deviation_m").get<double>();
  EXPECT_GT(deviation, 0.0);
  EXPECT_LT(deviation, 0.05);
  for (const auto& d : j.at("deviation")) EXPECT_LE(d.at("mean_deviation_m").get<double>(), d.at("max_deviation_m").get<double>());
}

}  // namespace
}  // namespace strata
