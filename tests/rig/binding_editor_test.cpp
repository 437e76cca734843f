// The binding editor core (rig/binding_editor.h) and the overrides file it writes (rig/binding.h): picking,
// visibility, screen selection on hand-made meshes with exact geometry and on the shipped default body; the
// edit -> save -> load -> bind round trip on every body level; undo; the mesh_vertices key; and
// `strata crowd --binding-overrides` on the real binary.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <sstream>

#include <glm/gtc/matrix_transform.hpp>

#include "io/hanim_loader.h"
#include "io/load_error.h"
#include "rig/binding.h"
#include "rig/binding_editor.h"
#include "rig/body_generator.h"
#include "rig/body_rig.h"
#include "tests/apps/strata_cli_runner.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
fs::path repo_data(const char* name) { return fs::path(STRATA_TEST_DATA) / ".." / ".." / "data" / name; }

// One scratch directory for the test program (CTest runs each test in a program of its own), removed when it exits.
fs::path scratch(const std::string& name) {
  static const test::TempDir dir("strata_binding_editor_test");
  return dir / name;
}

EditMesh edit_mesh(const Mesh& m) { return {m.positions, m.triangles}; }

// A grid of (n+1) x (n+1) vertices in the plane z = `z`, from (x0, y0) with `step` spacing, two triangles per
// cell; vertex (i, j) has index j * (n + 1) + i.
Mesh grid(int n, float x0, float y0, float step, float z, std::uint32_t first_index = 0) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.emplace_back(x0 + step * i, y0 + step * j, z);
  const auto at = [&](int i, int j) { return first_index + static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      m.triangles.insert(m.triangles.end(), {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j), at(i + 1, j + 1),
                                             at(i, j + 1)});
  return m;
}

Mesh merge(const Mesh& a, const Mesh& b) {
  Mesh m = a;
  const auto offset = static_cast<std::uint32_t>(a.positions.size());
  m.positions.insert(m.positions.end(), b.positions.begin(), b.positions.end());
  for (std::uint32_t i : b.triangles) m.triangles.push_back(i + offset);
  return m;
}

// Camera on +Z at distance 5 looking at the origin, 90 degree field of view, square 200 px viewport: a point
// (x, y, 0) lands on pixel (100 + 20 x, 100 - 20 y).
constexpr glm::ivec2 kSquare{200, 200};
glm::mat4 front_camera() {
  return glm::perspective(glm::radians(90.0f), 1.0f, 0.05f, 500.0f) *
         glm::lookAt(glm::vec3(0.0f, 0.0f, 5.0f), glm::vec3(0.0f), glm::vec3(0.0f, 1.0f, 0.0f));
}

// Orthographic camera whose world x, y are pixel x, (height - pixel y): exact pixel positions for selection tests.
constexpr glm::ivec2 kPixels{320, 240};
glm::mat4 pixel_camera() { return glm::ortho(0.0f, 320.0f, 0.0f, 240.0f, -10.0f, 10.0f); }

// ---- pick_ray / pick_vertex -------------------------------------------------------------------------------------

TEST(PickRay, ThroughAPixelPointsFromTheEyeThroughThatPoint) {
  const PickRay ray = pick_ray(front_camera(), {120.0f, 80.0f}, kSquare);  // the pixel of (1, 1, 0)
  const glm::vec3 expected = glm::normalize(glm::vec3(1.0f, 1.0f, -5.0f));
  EXPECT_NEAR(glm::length(ray.direction), 1.0f, 1e-6f);
  EXPECT_NEAR(ray.direction.x, expected.x, 1e-5f);
  EXPECT_NEAR(ray.direction.y, expected.y, 1e-5f);
  EXPECT_NEAR(ray.direction.z, expected.z, 1e-5f);
  // The origin is on the near plane, on the line from the eye.
  EXPECT_NEAR(ray.origin.z, 5.0f - 0.05f, 1e-5f);
  EXPECT_NEAR(ray.origin.x, 0.05f / 5.0f, 1e-5f);
  // The centre pixel looks straight ahead; y grows downwards.
  EXPECT_NEAR(pick_ray(front_camera(), {100.0f, 100.0f}, kSquare).direction.z, -1.0f, 1e-6f);
  EXPECT_LT(pick_ray(front_camera(), {100.0f, 150.0f}, kSquare).direction.y, 0.0f);
  EXPECT_THROW(pick_ray(front_camera(), {1.0f, 1.0f}, {0, 200}), std::invalid_argument);
  EXPECT_THROW(pick_ray(glm::mat4(0.0f), {1.0f, 1.0f}, kSquare), std::invalid_argument);
}

TEST(PickVertex, HitsTheNearestTrianglesClosestCorner) {
  // Back grid at z = 0 (-2..2, 0.5 apart), front grid at z = 1 covering x, y in 0..1 (0.25 apart).
  const Mesh back = grid(8, -2.0f, -2.0f, 0.5f, 0.0f);
  const Mesh front = grid(4, 0.0f, 0.0f, 0.25f, 1.0f);
  const Mesh both = merge(back, front);
  const auto back_index = [](int i, int j) { return static_cast<std::uint32_t>(j * 9 + i); };
  const auto front_index = [&](int i, int j) { return static_cast<std::uint32_t>(back.positions.size() + j * 5 + i); };

  // Just off the back vertex (-1, 1, 0) = grid (2, 6): the ray hits the back grid only.
  const glm::vec2 near_minus_one = {100.0f + 20.0f * -1.05f, 100.0f - 20.0f * 0.97f};
  EXPECT_EQ(pick_vertex(edit_mesh(both), pick_ray(front_camera(), near_minus_one, kSquare)), back_index(2, 6));
  // Through (0.5, 0.5, 0) the front grid is in the way: its vertex (0.5, 0.5, 1) = front (2, 2) is picked, not
  // the back grid's (0.5, 0.5, 0).
  const PickRay through_front = pick_ray(front_camera(), {110.0f, 90.0f}, kSquare);
  EXPECT_EQ(pick_vertex(edit_mesh(both), through_front), front_index(2, 2));
  EXPECT_EQ(pick_vertex(edit_mesh(back), through_front), back_index(5, 5));
  // Off the mesh, and pointing away from it: misses.
  EXPECT_FALSE(pick_vertex(edit_mesh(both), pick_ray(front_camera(), {2.0f, 2.0f}, kSquare)));
  EXPECT_FALSE(pick_vertex(edit_mesh(both), PickRay{{0.0f, 0.0f, 5.0f}, {0.0f, 0.0f, 1.0f}}));
}

TEST(PickVertex, DegenerateAndNonFiniteTrianglesAreSkipped) {
  const PickRay ray{{0.0f, 0.0f, 5.0f}, {0.0f, 0.0f, -1.0f}};
  // A triangle collapsed onto a segment through the ray, and one with a repeated corner.
  Mesh degenerate;
  degenerate.positions = {{-1.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, -1.0f, 0.5f},
                          {0.0f, 1.0f, 0.5f}};
  degenerate.triangles = {0, 1, 2, 3, 4, 4};
  EXPECT_FALSE(pick_vertex(edit_mesh(degenerate), ray));

  // A NaN corner in front of a good triangle: the good one is hit, not the NaN one.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Mesh mixed;
  mixed.positions = {{-1.0f, -1.0f, 1.0f}, {1.0f, -1.0f, 1.0f}, {0.0f, nan, 1.0f},
                     {-1.0f, -1.0f, 0.0f}, {1.0f, -1.0f, 0.0f}, {0.1f, 1.0f, 0.0f}};
  mixed.triangles = {0, 1, 2, 3, 4, 5};
  const std::optional<std::uint32_t> hit = pick_vertex(edit_mesh(mixed), ray);
  ASSERT_TRUE(hit);
  EXPECT_GE(*hit, 3u);
  // All NaN, and a NaN ray: no hit, no exception.
  Mesh all_nan = mixed;
  for (glm::vec3& p : all_nan.positions) p = glm::vec3(nan);
  EXPECT_FALSE(pick_vertex(edit_mesh(all_nan), ray));
  EXPECT_FALSE(pick_vertex(edit_mesh(mixed), PickRay{{0.0f, 0.0f, 5.0f}, glm::vec3(nan)}));
  // visible_vertices on the NaN mesh: NaN vertices are not visible, the good ones are.
  const std::vector<std::uint8_t> seen = visible_vertices(edit_mesh(mixed), front_camera(), kSquare);
  EXPECT_EQ(seen[2], 0);
  EXPECT_EQ(seen[5], 1);
  // A bad index is the caller's bug, not a silent miss.
  Mesh bad = mixed;
  bad.triangles.push_back(0), bad.triangles.push_back(1), bad.triangles.push_back(6);
  EXPECT_THROW(pick_vertex(edit_mesh(bad), ray), std::invalid_argument);
}

// ---- visibility and selection on exact geometry ----------------------------------------------------------------

TEST(VisibleVertices, AFrontPlaneHidesTheVerticesBehindItAndNoneOfItsOwn) {
  // Back grid 5..305 (step 20) at z = -1 (off the viewport's border lines, where rounding decides); a front grid
  // 100..200 x 60..160 (step 10) at z = +1. Orthographic, looking down -z: a back vertex is hidden exactly when
  // it lies inside the front square.
  const Mesh back = grid(15, 5.0f, 5.0f, 20.0f, -1.0f);
  const Mesh front = grid(10, 100.0f, 60.0f, 10.0f, 1.0f);
  const Mesh both = merge(back, front);
  // The ortho camera sees z = -10..10 and looks along -z: the front grid is the nearer.
  const glm::mat4 camera = pixel_camera();
  const std::vector<std::uint8_t> seen = visible_vertices(edit_mesh(both), camera, kPixels);
  ASSERT_EQ(seen.size(), both.positions.size());
  std::size_t hidden = 0;
  for (std::size_t v = 0; v < back.positions.size(); ++v) {
    const glm::vec3 p = back.positions[v];
    const bool covered = p.x > 100.0f && p.x < 200.0f && p.y > 60.0f && p.y < 160.0f;
    const bool on_screen = p.x <= 320.0f && p.y <= 240.0f;
    EXPECT_EQ(seen[v], on_screen && !covered ? 1 : 0) << "back vertex at " << p.x << ", " << p.y;
    hidden += covered;
  }
  EXPECT_EQ(hidden, 5u * 5u) << "x = 105..185, y = 65..145";
  for (std::size_t v = back.positions.size(); v < both.positions.size(); ++v)
    EXPECT_EQ(seen[v], 1) << "a vertex of the front grid is hidden by its own triangles";
  // Nearer than the near plane: not visible.
  const std::vector<std::uint8_t> turned =
      visible_vertices(edit_mesh(both), camera * glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, 30)), kPixels);
  EXPECT_EQ(std::count(turned.begin(), turned.end(), 1), 0);
}

TEST(SelectRect, CornersInAnyOrderAndReplaceAddSubtract) {
  // Vertices every 10 pixels, (5 + 10 i, 5 + 10 j) for i, j = 0..40, pixel y = 240 - world y: the viewport
  // shows x = 5..315, y = 5..235 of it (none on its border lines, where rounding decides).
  const Mesh m = grid(40, 5.0f, 5.0f, 10.0f, 0.0f);
  const EditMesh em = edit_mesh(m);
  VertexSelection sel(m.positions.size());
  auto expected_in = [&](float x0, float x1, float py0, float py1) {
    std::set<std::uint32_t> out;
    for (std::uint32_t v = 0; v < m.positions.size(); ++v) {
      const float px = m.positions[v].x, py = 240.0f - m.positions[v].y;
      if (px >= x0 && px <= x1 && py >= py0 && py <= py1 && px <= 320.0f && py >= 0.0f) out.insert(v);
    }
    return out;
  };
  auto as_set = [](const VertexSelection& s) {
    const std::vector<std::uint32_t> ids = s.ids();
    EXPECT_TRUE(std::is_sorted(ids.begin(), ids.end()));
    EXPECT_EQ(ids.size(), s.count());
    return std::set<std::uint32_t>(ids.begin(), ids.end());
  };
  // Replace, corners given bottom-right first. (Box edges stay off the vertices: a vertex exactly on an edge is
  // in or out by rounding.)
  select_rect(em, pixel_camera(), kPixels, {100.0f, 204.0f}, {50.0f, 146.0f}, {}, SelectOp::Replace, sel);
  const std::set<std::uint32_t> a = expected_in(50, 100, 146, 204);
  EXPECT_EQ(as_set(sel), a);
  EXPECT_EQ(a.size(), 5u * 5u) << "x = 55..95, y = 45..85";
  // Add a second box overlapping the first.
  select_rect(em, pixel_camera(), kPixels, {80.0f, 126.0f}, {158.0f, 184.0f}, {}, SelectOp::Add, sel);
  std::set<std::uint32_t> ab = a;
  for (std::uint32_t v : expected_in(80, 158, 126, 184)) ab.insert(v);
  EXPECT_GT(ab.size(), a.size());
  EXPECT_EQ(as_set(sel), ab);
  // Subtract a box through both.
  select_rect(em, pixel_camera(), kPixels, {0.0f, 170.0f}, {320.0f, 180.0f}, {}, SelectOp::Subtract, sel);
  std::set<std::uint32_t> abc;
  const std::set<std::uint32_t> c = expected_in(0, 320, 170, 180);
  for (std::uint32_t v : ab)
    if (!c.count(v)) abc.insert(v);
  EXPECT_EQ(as_set(sel), abc);
  EXPECT_LT(abc.size(), ab.size());
  // Replace again drops everything else.
  select_rect(em, pixel_camera(), kPixels, {0.0f, 0.0f}, {6.0f, 6.0f}, {}, SelectOp::Replace, sel);
  EXPECT_EQ(as_set(sel), expected_in(0, 6, 0, 6));
  EXPECT_EQ(sel.count(), 1u);
  // Vertices off the viewport (x > 320) are never selected, even by a box reaching there.
  select_rect(em, pixel_camera(), kPixels, {290.0f, 0.0f}, {1000.0f, 240.0f}, {}, SelectOp::Replace, sel);
  for (std::uint32_t v : sel.ids()) EXPECT_LE(m.positions[v].x, 320.0f);
  EXPECT_EQ(sel.count(), 3u * 24u) << "x = 295..315, y = 5..235";
  VertexSelection wrong(3);
  EXPECT_THROW(select_rect(em, pixel_camera(), kPixels, {0, 0}, {1, 1}, {}, SelectOp::Add, wrong),
               std::invalid_argument);
}

TEST(SelectBrush, SelectsExactlyTheVerticesWithinTheRadius) {
  const Mesh m = grid(30, 0.0f, 0.0f, 10.0f, 0.0f);
  VertexSelection sel(m.positions.size());
  for (float radius : {0.5f, 10.5f, 25.0f, 44.0f}) {
    const glm::vec2 centre{153.0f, 118.0f};
    select_brush(edit_mesh(m), pixel_camera(), kPixels, centre, radius, {}, SelectOp::Replace, sel);
    std::size_t expected = 0;
    for (std::uint32_t v = 0; v < m.positions.size(); ++v) {
      const glm::vec2 px{m.positions[v].x, 240.0f - m.positions[v].y};
      const bool inside = glm::length(px - centre) <= radius;
      EXPECT_EQ(sel.contains(v), inside) << "radius " << radius << ", vertex at " << px.x << ", " << px.y;
      expected += inside;
    }
    EXPECT_EQ(sel.count(), expected);
    if (radius > 10.0f) {
      EXPECT_GT(expected, 0u);
    }
  }
  // Subtract with a brush.
  select_brush(edit_mesh(m), pixel_camera(), kPixels, {150.0f, 120.0f}, 44.0f, {}, SelectOp::Replace, sel);
  const std::size_t before = sel.count();
  select_brush(edit_mesh(m), pixel_camera(), kPixels, {150.0f, 120.0f}, 10.5f, {}, SelectOp::Subtract, sel);
  EXPECT_EQ(sel.count(), before - 5u) << "the centre and its four neighbours";
  EXPECT_FALSE(sel.contains(15 + 12 * 31));
}

TEST(VertexSelection, SetClearAndBounds) {
  VertexSelection s(5);
  EXPECT_EQ(s.vertex_count(), 5u);
  s.set(3, true);
  s.set(3, true);
  s.set(1, true);
  EXPECT_EQ(s.count(), 2u);
  EXPECT_EQ(s.ids(), (std::vector<std::uint32_t>{1, 3}));
  s.set(3, false);
  EXPECT_FALSE(s.contains(3));
  EXPECT_FALSE(s.contains(99));
  EXPECT_THROW(s.set(5, true), std::out_of_range);
  s.clear();
  EXPECT_EQ(s.count(), 0u);
}

// ---- the shipped body ---------------------------------------------------------------------------------------------

constexpr glm::ivec2 kView{640, 480};
glm::mat4 body_camera(const glm::vec3& eye) {
  return glm::perspective(0.8f, 640.0f / 480.0f, 0.05f, 500.0f) *
         glm::lookAt(eye, glm::vec3(0.0f, 0.9f, 0.0f), glm::vec3(0.0f, 1.0f, 0.0f));
}

TEST(VisibleVertices, DefaultBodySeenFromTheFrontHidesItsBack) {
  const Mesh& body = default_bound_body()->levels[1].mesh;
  const glm::mat4 camera = body_camera({0.0f, 0.9f, 3.0f});  // H-Anim bodies face +Z
  const std::vector<std::uint8_t> seen = visible_vertices(edit_mesh(body), camera, kView);
  // The trunk between chest and hips, away from the arms: its front faces the camera, its back faces away.
  std::size_t front = 0, front_seen = 0, back = 0, back_seen = 0;
  for (std::size_t v = 0; v < body.vertex_count(); ++v) {
    const glm::vec3 p = body.positions[v];
    if (std::abs(p.x) > 0.08f || p.y < 0.95f || p.y > 1.35f) continue;
    if (body.normals[v].z > 0.5f) ++front, front_seen += seen[v];
    if (body.normals[v].z < -0.5f) ++back, back_seen += seen[v];
  }
  ASSERT_GT(front, 50u);
  ASSERT_GT(back, 50u);
  EXPECT_EQ(front_seen, front) << "every front trunk vertex is visible";
  EXPECT_EQ(back_seen, 0u) << "no back trunk vertex is visible";
  // And the other way round from behind.
  const std::vector<std::uint8_t> behind = visible_vertices(edit_mesh(body), body_camera({0.0f, 0.9f, -3.0f}), kView);
  std::size_t back_from_behind = 0, front_from_behind = 0;
  for (std::size_t v = 0; v < body.vertex_count(); ++v) {
    const glm::vec3 p = body.positions[v];
    if (std::abs(p.x) > 0.08f || p.y < 0.95f || p.y > 1.35f) continue;
    if (body.normals[v].z < -0.5f) back_from_behind += behind[v];
    if (body.normals[v].z > 0.5f) front_from_behind += behind[v];
  }
  EXPECT_EQ(back_from_behind, back);
  EXPECT_EQ(front_from_behind, 0u);
}

TEST(SelectRect, OnTheDefaultBodyVisibilityKeepsTheBackOut) {
  const Mesh& body = default_bound_body()->levels[1].mesh;
  const glm::mat4 camera = body_camera({0.0f, 0.9f, 3.0f});
  const std::vector<std::uint8_t> seen = visible_vertices(edit_mesh(body), camera, kView);
  VertexSelection through(body.vertex_count()), visible_only(body.vertex_count());
  const glm::vec2 a{0.0f, 0.0f}, b{640.0f, 480.0f};
  select_rect(edit_mesh(body), camera, kView, a, b, {}, SelectOp::Replace, through);
  select_rect(edit_mesh(body), camera, kView, a, b, seen, SelectOp::Replace, visible_only);
  EXPECT_EQ(through.count(), body.vertex_count()) << "the whole body is in the frame";
  EXPECT_EQ(visible_only.count(), static_cast<std::size_t>(std::count(seen.begin(), seen.end(), 1)));
  EXPECT_LT(visible_only.count(), body.vertex_count() * 3 / 4);
  EXPECT_GT(visible_only.count(), body.vertex_count() / 4);
  // The pick under the centre of the view is a visible vertex on the front of the body.
  const std::optional<std::uint32_t> hit =
      pick_vertex(edit_mesh(body), pick_ray(camera, {320.0f, 240.0f}, kView));
  ASSERT_TRUE(hit);
  EXPECT_EQ(seen[*hit], 1);
  EXPECT_GT(body.positions[*hit].z, 0.0f);
}

// ---- the editor ---------------------------------------------------------------------------------------------------

void expect_same_binding(const SkinBinding& a, const SkinBinding& b, const char* what) {
  ASSERT_EQ(a.vertex_count(), b.vertex_count()) << what;
  std::size_t differing = 0;
  for (std::size_t v = 0; v < a.vertex_count(); ++v) differing += a.joints[v] != b.joints[v] || a.weights[v] != b.weights[v];
  EXPECT_EQ(differing, 0u) << what;
}

std::size_t differing_vertices(const SkinBinding& a, const SkinBinding& b) {
  std::size_t n = 0;
  for (std::size_t v = 0; v < a.vertex_count(); ++v) n += a.joints[v] != b.joints[v] || a.weights[v] != b.weights[v];
  return n;
}

// The shipped body's pixel position of a world point, for brushing "around a joint".
glm::vec2 pixel_of(const glm::mat4& camera, const glm::vec3& p, glm::ivec2 viewport) {
  const glm::vec4 c = camera * glm::vec4(p, 1.0f);
  return {(c.x / c.w + 1.0f) * 0.5f * viewport.x, (1.0f - c.y / c.w) * 0.5f * viewport.y};
}

struct HipEdit {
  BindingEditor editor;
  int joint;
  std::vector<std::uint32_t> edited;
};

// Level `level` of the shipped body with the visible vertices around the left hip brushed and bound to l_hip.
HipEdit edit_around_left_hip(std::size_t level) {
  const Skeleton sk = load_default_humanoid().skeleton;
  const BodyLevel& l = default_bound_body()->levels[level];
  HipEdit e{BindingEditor(l.mesh, sk, l.binding, shipped_binding_tables()), sk.find_joint("l_hip"), {}};
  const glm::mat4 camera = body_camera({0.0f, 0.9f, 3.0f});
  const std::vector<std::uint8_t> seen = visible_vertices(edit_mesh(l.mesh), camera, kView);
  select_brush(edit_mesh(l.mesh), camera, kView, pixel_of(camera, sk.centers[e.joint], kView), 25.0f, seen,
               SelectOp::Replace, e.editor.selection());
  e.edited = e.editor.selection().ids();
  return e;
}

TEST(BindingEditor, EditSaveLoadBindsLevelOneExactlyAndLeavesTheOtherLevelsAlone) {
  const Skeleton sk = load_default_humanoid().skeleton;
  const auto shipped = default_bound_body();
  HipEdit e = edit_around_left_hip(1);
  ASSERT_GT(e.edited.size(), 20u);
  ASSERT_TRUE(e.editor.bind_selection(e.joint, "left hip front"));
  EXPECT_EQ(e.editor.edit_count(), 1u);
  const SkinBinding& edited = e.editor.binding();
  EXPECT_GT(differing_vertices(edited, shipped->levels[1].binding), 0u) << "the edit changed nothing";

  // The edited vertices: weights sum to 1, exactly the chosen joint and its parent.
  const int parent = sk.parents[e.joint];
  ASSERT_GE(parent, 0);
  std::set<std::uint32_t> edited_set(e.edited.begin(), e.edited.end());
  for (std::uint32_t v : e.edited) {
    std::set<int> joints;
    double sum = 0.0;
    for (int k = 0; k < kMaxInfluences; ++k)
      if (edited.weights[v][k] > 0.0f) joints.insert(edited.joints[v][k]), sum += edited.weights[v][k];
    EXPECT_NEAR(sum, 1.0, 1e-6) << v;
    EXPECT_EQ(joints, (std::set<int>{e.joint, parent})) << v;
  }
  // Vertices outside the selection keep the shipped binding.
  for (std::size_t v = 0; v < edited.vertex_count(); ++v)
    if (!edited_set.count(static_cast<std::uint32_t>(v))) {
      ASSERT_EQ(edited.joints[v], shipped->levels[1].binding.joints[v]) << v;
      ASSERT_EQ(edited.weights[v], shipped->levels[1].binding.weights[v]) << v;
    }

  const fs::path file = scratch("hip_edit.json");
  e.editor.save(file);
  const BindingTables loaded = load_binding_tables(read_text(repo_data("part_joints.json")), read_text(file),
                                                   "part_joints.json", file.string());
  ASSERT_EQ(loaded.overrides.size(), shipped_binding_tables().overrides.size() + 1);
  EXPECT_EQ(loaded.overrides.back().name, "left hip front");
  EXPECT_EQ(loaded.overrides.back().mesh_vertices, shipped->levels[1].mesh.vertex_count());
  const auto& levels = shipped_body_levels().levels;
  expect_same_binding(bind_three_step(levels[1], sk, loaded), edited, "level 1 from the saved file");
  expect_same_binding(bind_three_step(levels[0], sk, loaded), shipped->levels[0].binding, "level 0");
  expect_same_binding(bind_three_step(levels[2], sk, loaded), shipped->levels[2].binding, "level 2");

  // The same through load_binding_overrides_file and bind_body, cage included.
  const BindingTables from_file = load_binding_overrides_file(file, shipped_binding_tables());
  EXPECT_EQ(from_file.part_joints, shipped_binding_tables().part_joints);
  const auto rebound = bind_body(levels, sk, BindingMethod::ThreeStep, &shipped_body_levels().cage, &from_file);
  expect_same_binding(rebound->levels[1].binding, edited, "bind_body level 1");
  expect_same_binding(rebound->levels[0].binding, shipped->levels[0].binding, "bind_body level 0");
  ASSERT_TRUE(rebound->cage && shipped->cage);
  expect_same_binding(rebound->cage->binding, shipped->cage->binding, "bind_body cage");
}

TEST(BindingEditor, UndoRestoresTheBindingBitExactly) {
  const auto shipped = default_bound_body();
  const Skeleton sk = load_default_humanoid().skeleton;
  HipEdit e = edit_around_left_hip(2);
  ASSERT_FALSE(e.editor.undo()) << "nothing to undo yet";
  ASSERT_TRUE(e.editor.bind_selection(e.joint));
  const SkinBinding after_first = e.editor.binding();
  // A second, overlapping edit to another joint (a root-ward one, so rigid: HumanoidRoot has no parent).
  const int root = sk.find_joint("HumanoidRoot");
  ASSERT_LT(sk.parents[root], 0);
  ASSERT_TRUE(e.editor.bind_selection(root, "rigid"));
  for (std::uint32_t v : e.edited) {
    EXPECT_EQ(e.editor.binding().influence_count(v), 1);
    EXPECT_EQ(e.editor.binding().joints[v][0], root);
    EXPECT_EQ(e.editor.binding().weights[v][0], 1.0f);
  }
  EXPECT_EQ(e.editor.tables().overrides.size(), shipped_binding_tables().overrides.size() + 2);
  EXPECT_EQ(e.editor.tables().overrides[shipped_binding_tables().overrides.size()].name, "edit 1");
  EXPECT_TRUE(e.editor.undo());
  expect_same_binding(e.editor.binding(), after_first, "after one undo");
  EXPECT_TRUE(e.editor.undo());
  expect_same_binding(e.editor.binding(), shipped->levels[2].binding, "after two undos");
  EXPECT_EQ(e.editor.tables().overrides.size(), shipped_binding_tables().overrides.size());
  EXPECT_EQ(e.editor.edit_count(), 0u);
  EXPECT_FALSE(e.editor.undo());
}

TEST(BindingEditor, RefusesAnEmptySelectionOrABadJointAndChangesNothing) {
  const auto shipped = default_bound_body();
  const Skeleton sk = load_default_humanoid().skeleton;
  const BodyLevel& l = shipped->levels[2];
  BindingEditor editor(l.mesh, sk, l.binding, shipped_binding_tables());
  EXPECT_FALSE(editor.bind_selection(sk.find_joint("l_hip"))) << "empty selection";
  editor.selection().set(7, true);
  EXPECT_FALSE(editor.bind_selection(-1));
  EXPECT_FALSE(editor.bind_selection(static_cast<int>(sk.joint_count())));
  editor.selection() = VertexSelection(3);
  editor.selection().set(1, true);
  EXPECT_FALSE(editor.bind_selection(0)) << "a selection of another mesh";
  EXPECT_EQ(editor.edit_count(), 0u);
  EXPECT_EQ(editor.tables().overrides.size(), shipped_binding_tables().overrides.size());
  expect_same_binding(editor.binding(), l.binding, "refused edits");
  // A joint whose name an overrides file cannot carry (not H-Anim).
  Skeleton odd = sk;
  odd.joint_names[sk.find_joint("l_knee")] = "my_knee";
  BindingEditor odd_editor(l.mesh, odd, l.binding, shipped_binding_tables());
  odd_editor.selection().set(7, true);
  EXPECT_FALSE(odd_editor.bind_selection(sk.find_joint("l_knee")));
  EXPECT_TRUE(odd_editor.bind_selection(sk.find_joint("l_hip")));
  EXPECT_THROW(BindingEditor(l.mesh, sk, shipped->levels[1].binding, shipped_binding_tables()), std::invalid_argument);
}

TEST(BindingEditor, WeightColoursRunFromBlueToRedAndShowTheSelection) {
  EXPECT_EQ(weight_heat_rgba(0.0f), 0xFFFF0000u) << "blue: bytes R, G, B, A = 0, 0, 255, 255";
  EXPECT_EQ(weight_heat_rgba(1.0f / 3.0f), 0xFF00FF00u) << "green";
  EXPECT_EQ(weight_heat_rgba(2.0f / 3.0f), 0xFF00FFFFu) << "yellow";
  EXPECT_EQ(weight_heat_rgba(1.0f), 0xFF0000FFu) << "red";
  EXPECT_EQ(weight_heat_rgba(2.0f), weight_heat_rgba(1.0f));
  EXPECT_EQ(weight_heat_rgba(std::numeric_limits<float>::quiet_NaN()), weight_heat_rgba(0.0f));
  // Red grows and blue falls along the ramp.
  std::uint32_t red = 0, blue = 255;
  for (int i = 0; i <= 30; ++i) {
    const std::uint32_t c = weight_heat_rgba(static_cast<float>(i) / 30.0f);
    EXPECT_GE(c & 0xFFu, red);
    EXPECT_LE((c >> 16) & 0xFFu, blue);
    red = c & 0xFFu, blue = (c >> 16) & 0xFFu;
  }

  const Skeleton sk = load_default_humanoid().skeleton;
  const BodyLevel& l = default_bound_body()->levels[2];
  BindingEditor editor(l.mesh, sk, l.binding, shipped_binding_tables());
  const int elbow = sk.find_joint("l_elbow");
  std::vector<std::uint32_t> rgba(l.mesh.vertex_count());
  editor.selection().set(0, true);
  editor.weight_colors(elbow, true, rgba);
  EXPECT_EQ(rgba[0], kSelectionRgba);
  std::size_t red_vertices = 0, blended = 0;
  for (std::size_t v = 1; v < rgba.size(); ++v) {
    float w = 0.0f;
    for (int k = 0; k < kMaxInfluences; ++k)
      if (l.binding.joints[v][k] == elbow) w += l.binding.weights[v][k];
    EXPECT_EQ(rgba[v], weight_heat_rgba(w)) << v;
    red_vertices += w == 1.0f;
    blended += w > 0.0f && w < 1.0f;
  }
  EXPECT_GT(red_vertices, 0u) << "the forearm";
  EXPECT_GT(blended, 0u) << "the elbow band";
  editor.weight_colors(elbow, false, rgba);
  EXPECT_NE(rgba[0], kSelectionRgba);
  std::vector<std::uint32_t> short_buffer(3);
  EXPECT_THROW(editor.weight_colors(elbow, false, short_buffer), std::invalid_argument);
}

// ---- the overrides file -------------------------------------------------------------------------------------------

void expect_same_selection(const SkinSelection& a, const SkinSelection& b) {
  SCOPED_TRACE(a.name);
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.mesh_vertices, b.mesh_vertices);
  EXPECT_EQ(a.center, b.center);
  EXPECT_EQ(a.radius, b.radius);
  EXPECT_EQ(a.box_min, b.box_min);
  EXPECT_EQ(a.box_max, b.box_max);
  EXPECT_EQ(a.parts, b.parts);
  EXPECT_EQ(a.joints, b.joints);
  EXPECT_EQ(a.blend, b.blend);
  EXPECT_EQ(a.falloff_m, b.falloff_m);
}

TEST(BindingOverridesJson, RoundTripsTheShippedFileFieldByField) {
  const std::string parts = read_text(repo_data("part_joints.json"));
  const BindingTables shipped = load_binding_tables(parts, read_text(repo_data("binding_overrides.json")), "p", "o");
  ASSERT_FALSE(shipped.overrides.empty());
  const std::string text = binding_overrides_json(shipped.overrides);
  const BindingTables again = load_binding_tables(parts, text, "p", "serialised");
  ASSERT_EQ(again.overrides.size(), shipped.overrides.size()) << text;
  for (std::size_t i = 0; i < shipped.overrides.size(); ++i) expect_same_selection(again.overrides[i], shipped.overrides[i]);
  // Readable: the shipped numbers come back as written ("0.94", not 0.9399999976158142), and a _doc points at
  // the format.
  EXPECT_NE(text.find("0.94"), std::string::npos) << text;
  EXPECT_EQ(text.find("0.93999"), std::string::npos) << text;
  EXPECT_NE(text.find("data/binding_overrides.json"), std::string::npos);
  EXPECT_EQ(binding_overrides_json(again.overrides), text) << "serialising is deterministic";
  EXPECT_EQ(text.find("step2_radii"), std::string::npos) << "no radii, no key";
}

TEST(BindingOverridesJson, RoundTripsTheMakeHumanBodysStepTwoRadii) {
  const BindingTables& makehuman = shipped_binding_tables(ShippedBody::MakeHuman);
  ASSERT_FALSE(makehuman.step2_radii.empty());
  const std::string text = binding_overrides_json(makehuman.overrides, makehuman.step2_radii);
  EXPECT_NE(text.find("\"l_knee\": 0.1"), std::string::npos) << text;
  const BindingTables again = load_binding_tables("", text, "", "serialised");
  EXPECT_EQ(again.step2_radii, makehuman.step2_radii);
  EXPECT_EQ(again.overrides.size(), makehuman.overrides.size());
  // An overrides file loaded onto the body keeps the body's radii (a file without any, as older saves are).
  const fs::path file = scratch("no_radii.json");
  {
    std::ofstream out(file);
    out << R"({"overrides": []})";
  }
  EXPECT_EQ(load_binding_overrides_file(file, makehuman).step2_radii, makehuman.step2_radii);
}

TEST(BindingOverridesJson, RandomSelectionsRoundTripExactly) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> coord(-2.0f, 2.0f), small(1e-6f, 0.5f);
  std::vector<SkinSelection> list;
  for (int i = 0; i < 200; ++i) {
    SkinSelection s;
    s.name = i % 7 == 0 ? "" : "sel \"" + std::to_string(i) + "\"\t";
    s.kind = static_cast<SkinSelection::Kind>(i % 3);
    if (s.kind == SkinSelection::Kind::Vertices) {
      for (int k = 0; k < i; ++k) s.vertices.push_back(static_cast<std::uint32_t>(rng() % 100000));
      s.mesh_vertices = i % 2 ? 100000u + static_cast<std::uint32_t>(i) : 0u;
    } else if (s.kind == SkinSelection::Kind::Sphere) {
      s.center = {coord(rng), coord(rng), coord(rng)};
      s.radius = small(rng);
    } else {
      s.box_min = {coord(rng), coord(rng), coord(rng)};
      s.box_max = s.box_min + glm::vec3(small(rng), small(rng), small(rng));
    }
    if (i % 4 == 1) s.parts = {"hip", "lThigh"};
    if (i % 5 == 2) s.joints = {"l_hip", "sacroiliac"};
    s.blend = i % 2 ? SkinSelection::Blend::NearestTwo : SkinSelection::Blend::Parent;
    s.falloff_m = i % 3 == 0 ? 0.0f : small(rng);
    list.push_back(std::move(s));
  }
  const BindingTables back = load_binding_tables("", binding_overrides_json(list), "", "random");
  ASSERT_EQ(back.overrides.size(), list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    expect_same_selection(back.overrides[i], list[i]);
  }
}

TEST(BindingOverridesJson, MeshVerticesSkipsOtherMeshesAndRangeChecksItsOwn) {
  const Skeleton sk = load_default_humanoid().skeleton;
  const auto& levels = shipped_body_levels().levels;
  const auto level1 = static_cast<std::uint32_t>(levels[1].vertex_count());
  const std::string parts = read_text(repo_data("part_joints.json"));
  // An id valid on level 0 only, tagged as a level-1 list: level 1 rejects it, level 0 and 2 skip the entry.
  const std::string text = R"({"overrides": [{"name": "l1", "vertices": [)" + std::to_string(level1 + 5) +
                           R"(], "mesh_vertices": )" + std::to_string(level1) + R"(, "joints": ["l_knee"]}]})";
  const BindingTables t = load_binding_tables(parts, text, "p", "o");
  ASSERT_EQ(t.overrides.size(), 1u);
  EXPECT_EQ(t.overrides[0].mesh_vertices, level1);
  EXPECT_THROW(bind_three_step(levels[1], sk, t), std::invalid_argument);
  BindingOptions no_overrides;
  no_overrides.apply_overrides = false;
  expect_same_binding(bind_three_step(levels[0], sk, t), bind_three_step(levels[0], sk, t, no_overrides),
                      "level 0 skips the level-1 list");
  // Without mesh_vertices the same list applies to every mesh that has the vertex.
  const BindingTables any = load_binding_tables(
      parts, R"({"overrides": [{"vertices": [)" + std::to_string(level1 + 5) + R"(], "joints": ["l_knee"]}]})", "p", "o");
  EXPECT_GT(differing_vertices(bind_three_step(levels[0], sk, any), bind_three_step(levels[0], sk, any, no_overrides)),
            0u);
  EXPECT_THROW(bind_three_step(levels[1], sk, any), std::invalid_argument);
}

void expect_load_error(const std::string& overrides, const std::string& needle) {
  try {
    load_binding_tables("", overrides, "p.json", "my_overrides.json");
    FAIL() << "expected a LoadError mentioning " << needle << " for " << overrides;
  } catch (const LoadError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(BindingOverridesJson, BadMeshVerticesNameTheEntry) {
  expect_load_error(R"({"overrides": [{"name": "ball", "sphere": {"center": [0,1,0], "radius": 0.1},
                       "mesh_vertices": 8923}]})",
                    "my_overrides.json: overrides[0] 'ball': 'mesh_vertices' is only valid with 'vertices'");
  expect_load_error(R"({"overrides": [{"box": {"min": [0,0,0], "max": [1,1,1]}, "mesh_vertices": 0}]})",
                    "overrides[0]: 'mesh_vertices' is only valid");
  expect_load_error(R"({"overrides": [{"vertices": [1]}, {"name": "neg", "vertices": [1], "mesh_vertices": -3}]})",
                    "overrides[1] 'neg': 'mesh_vertices' must be a non-negative integer");
  expect_load_error(R"({"overrides": [{"vertices": [1], "mesh_vertices": 1.5}]})", "overrides[0]: 'mesh_vertices'");
  expect_load_error(R"({"overrides": [{"vertices": [1], "mesh_vertices": "8923"}]})", "overrides[0]: 'mesh_vertices'");
  expect_load_error(R"({"overrides": [{"vertices": [1], "mesh_vertices": 4294967296}]})",
                    "overrides[0]: 'mesh_vertices'");
  expect_load_error(R"({"overrides": [{"mesh_vertices": 5}]})", "needs exactly one of");
}

TEST(BindingOverridesJson, OverridesFileErrorsNameTheFile) {
  const fs::path missing = scratch("no_such_overrides.json");
  fs::remove(missing);
  const fs::path empty = scratch("empty_overrides.json");
  std::ofstream(empty) << "\n";
  const fs::path broken = scratch("broken_overrides.json");
  std::ofstream(broken) << R"({"overrides": [{"name": "x", "vertices": [1], "mesh_vertices": -1}]})";
  for (const auto& [file, needle] : {std::pair{missing, std::string("cannot open")},
                                     std::pair{empty, std::string("empty file")},
                                     std::pair{broken, std::string("overrides[0] 'x'")}}) {
    try {
      load_binding_overrides_file(file, shipped_binding_tables());
      ADD_FAILURE() << "no error for " << file;
    } catch (const LoadError& e) {
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  }
}

// ---- strata crowd --binding-overrides -------------------------------------------------------------------------------

TEST(StrataCrowd, BindingOverridesFileRebindsTheShippedBody) {
  HipEdit e = edit_around_left_hip(2);
  ASSERT_TRUE(e.editor.bind_selection(e.joint));
  const fs::path file = scratch("crowd_overrides.json");
  e.editor.save(file);
  const fs::path out = scratch("crowd_out");
  const std::string common = "crowd --walkers 1 --frames 1 --width 64 --height 48 --level 2 --no-png --no-mp4 "
                             "--no-progress --table1-frames 0 --out " + out.string();
  const test::CliResult r = test::run_strata(common + " --binding-overrides " + file.string());
  ASSERT_EQ(r.status, 0) << r.out;
  const nlohmann::json table = nlohmann::json::parse(std::ifstream(out / "summary.json")).at("table1");
  ASSERT_EQ(table.size(), 3u);
  // Level 2 carries the edit, levels 0 and 1 the shipped binding (the edit's ids are level 2's).
  const BindingStats edited = binding_stats(e.editor.binding());
  EXPECT_EQ(table.at(2).at("vertices_one_joint").get<std::size_t>(), edited.one_joint);
  EXPECT_EQ(table.at(2).at("vertices_two_joints").get<std::size_t>(), edited.two_joints);
  EXPECT_NE(edited.two_joints, binding_stats(default_bound_body()->levels[2].binding).two_joints);
  for (int level = 0; level < 2; ++level)
    EXPECT_EQ(table.at(level).at("vertices_two_joints").get<std::size_t>(),
              binding_stats(default_bound_body()->levels[static_cast<std::size_t>(level)].binding).two_joints);

  // A bad file: one line naming it (and the entry), non-zero exit.
  const fs::path bad = scratch("bad_crowd_overrides.json");
  std::ofstream(bad) << R"({"overrides": [{"name": "oops", "sphere": {"center": [0,1,0], "radius": 0.1},
                            "mesh_vertices": 5133}]})";
  const test::CliResult b = test::run_strata(common + " --binding-overrides " + bad.string());
  EXPECT_NE(b.status, 0);
  EXPECT_EQ(std::count(b.out.begin(), b.out.end(), '\n'), 1) << b.out;
  EXPECT_NE(b.out.find(bad.string() + ": overrides[0] 'oops'"), std::string::npos) << b.out;
  // Only for the shipped body.
  const test::CliResult m = test::run_strata(common + " --binding-overrides " + file.string() + " --skeleton " +
                                             repo_data("default_skeleton.x3d").string());
  EXPECT_NE(m.status, 0);
  EXPECT_NE(m.out.find("--binding-overrides"), std::string::npos) << m.out;
}

}  // namespace
}  // namespace strata
