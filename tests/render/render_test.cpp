// Rendering tests on a real headless context (EGL surfaceless, llvmpipe in CI): no mocks. Instead of golden
// images, which would pin the exact Mesa build, the tests check geometry: lit pixels must fall where the camera
// maths says the skeleton projects to, and must be there at all.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <random>
#include <set>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <tbb/global_control.h>
#include <glm/mat4x4.hpp>
#include <glm/vec4.hpp>

#include "components/skeleton.h"
#include "io/image_writer.h"
#include "profiling/profiler.h"
#include "render/appearance.h"
#include "render/body_pass.h"
#include "render/camera.h"
#include "render/crowd_renderer.h"
#include "render/footprint.h"
#include "render/gl_context.h"
#include "render/gl_context_glfw.h"
#include "render/gl_program.h"
#include "render/ground_pass.h"
#include "render/skeleton_geometry.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr float kAspect = static_cast<float>(kWidth) / kHeight;

// A 14-joint stick figure, about 1.75 m tall, standing at the origin facing +Z.
Skeleton make_stick_figure() {
  struct J {
    const char* name;
    int parent;
    glm::vec3 at;
  };
  const J joints[] = {
      {"HumanoidRoot", -1, {0.0f, 1.0f, 0.0f}},      {"chest", 0, {0.0f, 1.35f, 0.0f}},
      {"neck", 1, {0.0f, 1.55f, 0.0f}},              {"skull_top", 2, {0.0f, 1.75f, 0.02f}},
      {"l_shoulder", 1, {0.18f, 1.5f, 0.0f}},        {"l_elbow", 4, {0.26f, 1.25f, 0.02f}},
      {"l_wrist", 5, {0.3f, 1.02f, 0.06f}},          {"r_shoulder", 1, {-0.18f, 1.5f, 0.0f}},
      {"r_elbow", 7, {-0.26f, 1.25f, -0.02f}},       {"r_wrist", 8, {-0.3f, 1.02f, -0.04f}},
      {"l_hip", 0, {0.1f, 0.95f, 0.0f}},             {"l_knee", 10, {0.11f, 0.5f, 0.04f}},
      {"l_ankle", 11, {0.12f, 0.06f, 0.0f}},         {"r_hip", 0, {-0.1f, 0.95f, 0.0f}},
  };
  Skeleton s;
  s.name = "stick";
  for (const J& j : joints) {
    s.joint_names.push_back(j.name);
    s.source_joint_names.push_back(j.name);
    s.parents.push_back(j.parent);
    s.centers.push_back(j.at);
  }
  s.limits.resize(s.joint_count());
  s.stiffness.assign(s.joint_count(), glm::vec3{1.0f});
  return s;
}

std::vector<glm::vec3> translated(const std::vector<glm::vec3>& points, const glm::vec3& offset) {
  std::vector<glm::vec3> out;
  for (const glm::vec3& p : points) out.push_back(p + offset);
  return out;
}

struct Pixel {
  float x, y, w;  // pixel coordinates (origin top-left, y down) and clip w (depth along the view axis)
};

Pixel project(const glm::vec3& p, const glm::mat4& view, const glm::mat4& projection) {
  const glm::vec4 clip = projection * view * glm::vec4(p, 1.0f);
  const glm::vec3 ndc = glm::vec3(clip) / clip.w;
  return {(ndc.x * 0.5f + 0.5f) * kWidth, (0.5f - ndc.y * 0.5f) * kHeight, clip.w};
}

struct Rect {
  float x0 = 1e30f, y0 = 1e30f, x1 = -1e30f, y1 = -1e30f;
  bool contains_pixel(int x, int y) const {
    const float cx = static_cast<float>(x) + 0.5f, cy = static_cast<float>(y) + 0.5f;
    return cx >= x0 && cx <= x1 && cy >= y0 && cy <= y1;
  }
  bool overlaps(const Rect& o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
};

// Bounding rectangle of the projected joints, grown by a conservative pixel margin for the geometry's radius.
// All geometry lies within R = max(bone, joint radius) of the joint-to-joint segments, and the projection of a
// segment lies inside the rectangle of its projected ends. A sphere of radius R at view depth z covers at most
// f * R / (z - R) pixels on the axis (f = focal length in pixels); off-axis it stretches by 1 / cos^2 of the
// angle, under 1.3 in these views, so twice that plus 2 pixels of rasterisation/MSAA coverage is safe.
Rect projected_bounds(const std::vector<glm::vec3>& joints, const glm::mat4& view, const glm::mat4& projection,
                      const RenderOptions& options) {
  const float radius = std::max(options.bone_radius, options.joint_radius);
  const float focal_pixels = projection[1][1] * 0.5f * kHeight;
  Rect r;
  float margin = 0.0f;
  for (const glm::vec3& j : joints) {
    const Pixel p = project(j, view, projection);
    EXPECT_GT(p.w, radius) << "test setup: joint behind the near side of the camera";
    r.x0 = std::min(r.x0, p.x);
    r.x1 = std::max(r.x1, p.x);
    r.y0 = std::min(r.y0, p.y);
    r.y1 = std::max(r.y1, p.y);
    margin = std::max(margin, 2.0f * focal_pixels * radius / (p.w - radius) + 2.0f);
  }
  r.x0 -= margin;
  r.y0 -= margin;
  r.x1 += margin;
  r.y1 += margin;
  return r;
}

using Rgba = std::array<std::uint8_t, 4>;

Rgba pixel_at(const std::vector<std::uint8_t>& image, int x, int y) {
  const std::size_t i = (static_cast<std::size_t>(y) * kWidth + static_cast<std::size_t>(x)) * 4;
  return {image[i], image[i + 1], image[i + 2], image[i + 3]};
}

class RenderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    try {
      context_ = create_headless_gl_context();
    } catch (const std::exception& e) {
      FAIL() << "headless GL context unavailable (CI has Mesa, so this is a failure): " << e.what();
    }
    options_.draw_ground = false;
    renderer_ = std::make_unique<CrowdRenderer>(kWidth, kHeight, options_);
    background_ = render_background();
  }

  void TearDown() override {
    renderer_.reset();  // needs the context current
    context_.reset();
  }

  // The clear colour as the framebuffer stores it, read from an empty frame (no assumption about rounding).
  Rgba render_background() {
    std::vector<std::uint8_t> image = render({}, 0, OrbitCamera{});
    const Rgba first = pixel_at(image, 0, 0);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x)
        if (pixel_at(image, x, y) != first) {
          ADD_FAILURE() << "empty frame is not uniform at " << x << "," << y;
          return first;
        }
    return first;
  }

  std::vector<std::uint8_t> render(const std::vector<glm::vec3>& positions, std::size_t walkers,
                                   const OrbitCamera& camera) {
    SkeletonDrawInput input;
    input.skeleton = &skeleton_;
    input.joint_positions = positions;
    input.walker_count = walkers;
    renderer_->render(input, camera.view(), camera.projection(kAspect));
    std::vector<std::uint8_t> image;
    renderer_->read_rgba(image);
    return image;
  }

  bool is_background(const std::vector<std::uint8_t>& image, int x, int y) const {
    return pixel_at(image, x, y) == background_;
  }

  // Renders one figure and checks the three properties of the brief: every lit pixel inside the projected
  // bounds, plenty of lit pixels, and lit pixels on the middle of two bones.
  void check_single_figure(const std::vector<glm::vec3>& joints, const OrbitCamera& camera) {
    const std::vector<std::uint8_t> image = render(joints, 1, camera);
    const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
    const Rect bounds = projected_bounds(joints, view, projection, options_);
    int inside = 0, outside = 0;
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) {
        if (is_background(image, x, y)) continue;
        if (bounds.contains_pixel(x, y))
          ++inside;
        else if (++outside <= 3)
          ADD_FAILURE() << "lit pixel at " << x << "," << y << " outside [" << bounds.x0 << "," << bounds.x1
                        << "]x[" << bounds.y0 << "," << bounds.y1 << "]";
      }
    EXPECT_EQ(outside, 0);
    EXPECT_GT(inside, 200);
    // Spine (root -> chest) and left thigh (hip -> knee), both about 0.4 m long.
    for (auto [a, b] : {std::pair{0, 1}, std::pair{10, 11}}) {
      const Pixel mid = project(0.5f * (joints[a] + joints[b]), view, projection);
      const int x = static_cast<int>(std::floor(mid.x)), y = static_cast<int>(std::floor(mid.y));
      ASSERT_TRUE(x >= 0 && x < kWidth && y >= 0 && y < kHeight) << "test setup: bone midpoint off screen";
      EXPECT_FALSE(is_background(image, x, y)) << "bone " << a << "->" << b << " midpoint pixel " << x << ","
                                               << y << " shows the clear colour";
    }
  }

  std::unique_ptr<GlContext> context_;
  RenderOptions options_;
  std::unique_ptr<CrowdRenderer> renderer_;
  Skeleton skeleton_ = make_stick_figure();
  Rgba background_{};
};

OrbitCamera figure_camera() {
  OrbitCamera camera;
  camera.target = {0.0f, 0.9f, 0.0f};
  camera.distance = 3.0f;
  camera.yaw = 0.6f;
  camera.pitch = 0.25f;
  return camera;
}

TEST_F(RenderTest, ContextIsGl45CoreWithARenderer) {
  EXPECT_FALSE(context_->renderer().empty());
  const std::string version = context_->version();
  int major = 0, minor = 0;
  ASSERT_EQ(std::sscanf(version.c_str(), "%d.%d", &major, &minor), 2) << version;
  EXPECT_TRUE(major > 4 || (major == 4 && minor >= 5)) << version;
}

TEST_F(RenderTest, BackgroundIsTheClearColour) {
  for (int c = 0; c < 4; ++c)
    EXPECT_NEAR(background_[static_cast<std::size_t>(c)], options_.clear_color[c] * 255.0f, 1.0f) << "channel " << c;
}

TEST_F(RenderTest, FigurePixelsLieInsideProjectedBounds) {
  check_single_figure(skeleton_.centers, figure_camera());
}

TEST_F(RenderTest, FigurePixelsLieInsideProjectedBoundsFromBehindAndAbove) {
  OrbitCamera camera = figure_camera();
  camera.yaw = -2.3f;
  camera.pitch = 0.7f;
  camera.distance = 3.4f;
  check_single_figure(skeleton_.centers, camera);
}

TEST_F(RenderTest, OffCentreFigureIsDrawnWhereItProjects) {
  const OrbitCamera camera = figure_camera();
  const std::vector<glm::vec3> joints = translated(skeleton_.centers, {0.9f, 0.0f, -0.5f});
  const Rect bounds = projected_bounds(joints, camera.view(), camera.projection(kAspect), options_);
  // The check below only proves the projection is used if the figure is clearly away from the centre.
  ASSERT_GT(std::abs(0.5f * (bounds.x0 + bounds.x1) - 0.5f * kWidth), 30.0f);
  check_single_figure(joints, camera);
}

TEST_F(RenderTest, GridOfWalkersEachDrawnInItsOwnBox) {
  constexpr int kSide = 3;
  constexpr float kSpacing = 2.0f;
  std::vector<glm::vec3> positions;
  std::vector<std::vector<glm::vec3>> walkers;
  for (int row = 0; row < kSide; ++row)
    for (int col = 0; col < kSide; ++col) {
      const glm::vec3 offset{(static_cast<float>(col) - 1.0f) * kSpacing, 0.0f,
                             (static_cast<float>(row) - 1.0f) * kSpacing};
      walkers.push_back(translated(skeleton_.centers, offset));
      positions.insert(positions.end(), walkers.back().begin(), walkers.back().end());
    }
  glm::vec3 lo{1e9f}, hi{-1e9f};
  for (const glm::vec3& p : positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  OrbitCamera camera;
  camera.yaw = 0.25f;
  camera.pitch = 1.0f;  // high enough that the rows do not hide each other
  camera.frame_box(lo, hi, kAspect);

  const std::vector<std::uint8_t> image = render(positions, walkers.size(), camera);
  std::vector<Rect> boxes;
  for (const auto& w : walkers)
    boxes.push_back(projected_bounds(w, camera.view(), camera.projection(kAspect), options_));
  // Disjoint boxes make "pixels in each box" mean "each walker was drawn", not "a neighbour overlaps".
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    EXPECT_TRUE(boxes[i].x0 >= 0.0f && boxes[i].y0 >= 0.0f && boxes[i].x1 <= kWidth && boxes[i].y1 <= kHeight)
        << "frame_box left walker " << i << " partly out of view";
    for (std::size_t j = i + 1; j < boxes.size(); ++j)
      ASSERT_FALSE(boxes[i].overlaps(boxes[j])) << "test setup: boxes " << i << " and " << j << " overlap";
  }

  std::vector<int> lit(boxes.size(), 0);
  int outside = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      if (is_background(image, x, y)) continue;
      bool in_any = false;
      for (std::size_t i = 0; i < boxes.size(); ++i)
        if (boxes[i].contains_pixel(x, y)) {
          ++lit[i];
          in_any = true;
        }
      if (!in_any) ++outside;
    }
  EXPECT_EQ(outside, 0);
  for (std::size_t i = 0; i < lit.size(); ++i) EXPECT_GT(lit[i], 80) << "walker " << i;
}

// A closed box as a body mesh: 24 vertices (flat faces), 12 counter-clockwise triangles.
void add_box(const glm::vec3& lo, const glm::vec3& hi, std::vector<glm::vec3>& positions, std::vector<glm::vec3>& normals,
             std::vector<std::uint32_t>* triangles) {
  const glm::vec3 c = 0.5f * (lo + hi), h = 0.5f * (hi - lo);
  for (int axis = 0; axis < 3; ++axis)
    for (float sign : {-1.0f, 1.0f}) {
      glm::vec3 n(0.0f);
      n[axis] = sign;
      const glm::vec3 u = glm::vec3(n.y, n.z, n.x), v = glm::cross(n, u);  // u x v = n: counter-clockwise
      const auto base = static_cast<std::uint32_t>(positions.size());
      for (auto [a, b] : {std::pair{-1.0f, -1.0f}, std::pair{1.0f, -1.0f}, std::pair{1.0f, 1.0f}, std::pair{-1.0f, 1.0f}}) {
        positions.push_back(c + h * (n + a * u + b * v));
        normals.push_back(n);
      }
      if (triangles) triangles->insert(triangles->end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    }
}

// Two box "walkers" sharing one topology, in the skin system's SoA: six component arrays, walker blocks `stride`
// apart. Walker 0 spans x -0.8..-0.4, walker 1 x 0.4..0.8.
struct TwoBoxBodies {
  std::vector<glm::vec3> positions, normals;
  std::vector<std::uint32_t> triangles;
  std::vector<float> soa[6];
  std::size_t per_walker = 0;

  TwoBoxBodies() {
    add_box({-0.8f, 0.5f, -0.2f}, {-0.4f, 1.5f, 0.2f}, positions, normals, &triangles);
    per_walker = positions.size();
    add_box({0.4f, 0.3f, -0.2f}, {0.8f, 1.2f, 0.2f}, positions, normals, nullptr);  // walker 2, same topology
    for (std::size_t v = 0; v < positions.size(); ++v)
      for (int c = 0; c < 3; ++c) {
        soa[c].push_back(positions[v][c]);
        soa[3 + c].push_back(normals[v][c]);
      }
  }
  BodyDrawInput input() const {
    BodyDrawInput in;
    in.triangles = triangles;
    in.px = soa[0].data(), in.py = soa[1].data(), in.pz = soa[2].data();
    in.nx = soa[3].data(), in.ny = soa[4].data(), in.nz = soa[5].data();
    in.stride = per_walker, in.vertex_count = per_walker, in.walker_count = 2;
    return in;
  }
};

TEST_F(RenderTest, BodiesAreDrawnWhereTheyProjectAndNowhereElse) {
  const TwoBoxBodies boxes;
  const std::vector<glm::vec3>& positions = boxes.positions;
  const std::vector<std::uint32_t>& triangles = boxes.triangles;
  const std::size_t per_walker = boxes.per_walker;
  renderer_->options().draw_ground = false;
  renderer_->options().draw_skeleton = false;
  BodyDrawInput bodies = boxes.input();
  const OrbitCamera camera = figure_camera();
  renderer_->render(SkeletonDrawInput{}, camera.view(), camera.projection(kAspect), &bodies);
  std::vector<std::uint8_t> image;
  renderer_->read_rgba(image);
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  RenderOptions no_margin = options_;
  no_margin.bone_radius = no_margin.joint_radius = 0.0f;
  const Rect a = projected_bounds({positions.begin(), positions.begin() + 24}, view, projection, no_margin);
  const Rect b = projected_bounds({positions.begin() + 24, positions.end()}, view, projection, no_margin);
  int lit = 0, outside = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      if (is_background(image, x, y)) continue;
      ++lit;
      outside += !a.contains_pixel(x, y) && !b.contains_pixel(x, y);
    }
  EXPECT_EQ(outside, 0);
  EXPECT_GT(lit, 500);
  for (const glm::vec3& centre : {glm::vec3(-0.6f, 1.0f, 0.0f), glm::vec3(0.6f, 0.75f, 0.0f)}) {
    const Pixel p = project(centre, view, projection);
    const Rgba c = pixel_at(image, static_cast<int>(p.x), static_cast<int>(p.y));
    EXPECT_FALSE(is_background(image, static_cast<int>(p.x), static_cast<int>(p.y)));
    EXPECT_GT(c[0], c[2]) << "skin is warmer than blue";
  }
  std::vector<std::uint32_t> bad = triangles;
  bad[5] = static_cast<std::uint32_t>(per_walker);
  BodyDrawInput broken = bodies;
  broken.triangles = bad;
  EXPECT_THROW(renderer_->render(SkeletonDrawInput{}, view, projection, &broken), std::invalid_argument);
}

// Per-vertex colours (the binding editor's weight display): walker 1 tinted pure blue with full alpha turns
// blue; walker 0 with alpha 0 keeps the skin colour; and a later draw without colours is plain skin again (the
// disabled attribute must not keep the last tint).
TEST_F(RenderTest, PerVertexColoursTintOnlyWhereTheirAlphaSays) {
  const TwoBoxBodies boxes;
  const std::size_t per_walker = boxes.per_walker;
  const std::vector<glm::vec3>& positions = boxes.positions;
  renderer_->options().draw_ground = false;
  renderer_->options().draw_skeleton = false;
  std::vector<std::uint32_t> rgba(positions.size(), 0x00ff0000u);  // blue, alpha 0: no tint
  for (std::size_t v = per_walker; v < positions.size(); ++v) rgba[v] = 0xffff0000u;  // blue, opaque
  BodyDrawInput bodies = boxes.input();
  bodies.rgba = rgba.data();
  const OrbitCamera camera = figure_camera();
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  const auto colour_at = [&](const glm::vec3& centre) {
    std::vector<std::uint8_t> image;
    renderer_->read_rgba(image);
    const Pixel p = project(centre, view, projection);
    return pixel_at(image, static_cast<int>(p.x), static_cast<int>(p.y));
  };
  const glm::vec3 walker0(-0.6f, 1.0f, 0.0f), walker1(0.6f, 0.75f, 0.0f);
  renderer_->render(SkeletonDrawInput{}, view, projection, &bodies);
  const Rgba skin = colour_at(walker0), tinted = colour_at(walker1);
  EXPECT_GT(skin[0], skin[2]) << "alpha 0 must leave the skin colour";
  EXPECT_GT(tinted[2], tinted[0] + 40) << "an opaque blue tint must turn the body blue";
  bodies.rgba = nullptr;
  renderer_->render(SkeletonDrawInput{}, view, projection, &bodies);
  const Rgba plain = colour_at(walker1);
  EXPECT_GT(plain[0], plain[2]) << "without colours the last tint must not stick";
}

float luminance(const Rgba& c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

// RenderQuality::High with the sun overhead: each box hangs above the ground and shadows it straight down, so
// the ground under a box is darker than the ground a metre in front of it, which no shadow reaches; at low
// quality (no shadows) the two are lit alike.
TEST_F(RenderTest, HighQualityBodiesShadowTheGroundUnderThem) {
  const TwoBoxBodies boxes;
  BodyDrawInput bodies = boxes.input();
  renderer_->options().draw_ground = true;
  renderer_->options().draw_skeleton = false;
  renderer_->options().to_sun = {0.0f, 1.0f, 0.0f};
  OrbitCamera camera = figure_camera();
  camera.target = {0.0f, 0.3f, 0.0f};
  camera.pitch = 0.7f;
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  const auto ground_ratio = [&](RenderQuality quality) {
    renderer_->options().quality = quality;
    renderer_->render(SkeletonDrawInput{}, view, projection, &bodies);
    std::vector<std::uint8_t> image;
    renderer_->read_rgba(image);
    const Pixel under = project({-0.6f, 0.0f, 0.0f}, view, projection), open = project({-0.6f, 0.0f, 1.0f}, view, projection);
    return luminance(pixel_at(image, static_cast<int>(under.x), static_cast<int>(under.y))) /
           luminance(pixel_at(image, static_cast<int>(open.x), static_cast<int>(open.y)));
  };
  EXPECT_LT(ground_ratio(RenderQuality::High), 0.75f);
  EXPECT_GT(ground_ratio(RenderQuality::Low), 0.95f);
}

// Each walker wears its key's palette (render/appearance.h), split per pixel at its surface cut: boxes whose
// upper half is the top and lower half the bottom show the palettes' colours where they should, and two keys
// with different shirts dress the two boxes differently.
TEST_F(RenderTest, HighQualityDressesEachWalkerInItsKeysColours) {
  const TwoBoxBodies boxes;
  // Two keys whose shirts differ most in red, and a first key whose shirt and trousers differ in red too.
  std::uint32_t k0 = 0, k1 = 1;
  float best = 0.0f;
  for (std::uint32_t a = 0; a < 60; ++a)
    for (std::uint32_t b = 0; b < 60; ++b) {
      const WalkerPalette pa = walker_palette(a), pb = walker_palette(b);
      const float shirts = pa[1].r - pb[1].r, halves = pa[1].r - pa[2].r;
      if (shirts > best && halves > 0.15f) best = shirts, k0 = a, k1 = b;
    }
  ASSERT_GT(best, 0.3f) << "test setup: the palettes have no two such keys";
  const std::uint32_t keys[2] = {k0, k1};
  const std::uint8_t top_over_bottom =
      static_cast<std::uint8_t>(static_cast<unsigned>(SurfaceMaterial::Top) | static_cast<unsigned>(SurfaceMaterial::Bottom) << 4);
  std::vector<std::uint8_t> materials(boxes.per_walker, top_over_bottom);
  std::vector<float> cut(boxes.per_walker);
  // Every box corner's distance to the cut: +1 above, -1 below, so each face splits at half its height.
  for (std::size_t v = 0; v < boxes.per_walker; ++v) cut[v] = boxes.positions[v].y > 1.0f ? 1.0f : -1.0f;
  BodyDrawInput bodies = boxes.input();
  bodies.walker_keys = keys;
  bodies.materials = materials;
  bodies.material_cut = cut;
  renderer_->options().quality = RenderQuality::High;
  renderer_->options().draw_ground = false;
  renderer_->options().draw_skeleton = false;
  const OrbitCamera camera = figure_camera();
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  renderer_->render(SkeletonDrawInput{}, view, projection, &bodies);
  std::vector<std::uint8_t> image;
  renderer_->read_rgba(image);
  const auto at = [&](const glm::vec3& p) {
    const Pixel q = project(p, view, projection);
    return pixel_at(image, static_cast<int>(q.x), static_cast<int>(q.y));
  };
  // Front faces (z = 0.2): walker 0 spans y 0.5..1.5 (cut at 1.0), walker 1 y 0.3..1.2 (cut at 0.75).
  const Rgba shirt0 = at({-0.6f, 1.3f, 0.2f}), trousers0 = at({-0.6f, 0.7f, 0.2f});
  const Rgba shirt1 = at({0.6f, 1.05f, 0.2f});
  EXPECT_GT(shirt0[0], trousers0[0] + 20) << "walker 0's shirt is redder than its trousers";
  EXPECT_GT(shirt0[0], shirt1[0] + 20) << "walker 0's shirt is redder than walker 1's";
}

// With a profiler set, each pass of a frame is its own scope; without one, nothing is recorded.
// ---- The ray tracer (render/ray_tracer.h, RenderOptions::backend) ---------------------------------------------

// The same frame of two dressed boxes over the ground, high quality, drawn by GL and traced by Embree: the two
// images agree but for edges (GL resolves 4x MSAA, the tracer shoots one ray a pixel) and shadow-map softness.
TEST_F(RenderTest, RayTracedFrameAgreesWithTheGlFrame) {
  const TwoBoxBodies boxes;
  BodyDrawInput bodies = boxes.input();
  const std::uint32_t keys[2] = {3, 11};
  bodies.walker_keys = keys;
  renderer_->options().draw_ground = true;
  renderer_->options().draw_skeleton = false;
  renderer_->options().quality = RenderQuality::High;
  OrbitCamera camera = figure_camera();
  camera.pitch = 0.35f;
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  std::vector<std::uint8_t> gl, traced;
  renderer_->render(SkeletonDrawInput{}, view, projection, &bodies);
  renderer_->read_rgba(gl);
  renderer_->options().backend = RenderBackend::RayTraced;
  renderer_->render(SkeletonDrawInput{}, view, projection, &bodies);
  renderer_->read_rgba(traced);
  ASSERT_EQ(gl.size(), traced.size());
  double total = 0.0;
  std::size_t far_off = 0, pixels = gl.size() / 4;
  for (std::size_t i = 0; i < pixels; ++i) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int d = std::abs(int(gl[4 * i + static_cast<std::size_t>(c)]) - int(traced[4 * i + static_cast<std::size_t>(c)]));
      total += d;
      worst = std::max(worst, d);
    }
    far_off += worst > 48;
  }
  const double mean = total / (3.0 * static_cast<double>(pixels));
  std::printf("GL vs traced: mean channel difference %.2f, pixels off by > 48: %.2f %%\n", mean,
              100.0 * static_cast<double>(far_off) / static_cast<double>(pixels));
  EXPECT_LT(mean, 4.0) << "mean channel difference, of 255";
  EXPECT_LT(static_cast<double>(far_off) / static_cast<double>(pixels), 0.03) << "pixels off by more than 48";
  // The boxes are there in the traced image, in their own shirts.
  const Pixel box0 = project({-0.6f, 1.3f, 0.2f}, view, projection), box1 = project({0.6f, 1.0f, 0.2f}, view, projection);
  const Rgba a = pixel_at(traced, static_cast<int>(box0.x), static_cast<int>(box0.y));
  const Rgba b = pixel_at(traced, static_cast<int>(box1.x), static_cast<int>(box1.y));
  EXPECT_NE(a, background_);
  EXPECT_NE(a, b) << "two keys, two shirts";
  EXPECT_GT(renderer_->triangles_drawn(), 0u);
}

// The sun overhead: the ground under a traced box is in its shadow ray's way, a metre in front of it is not.
TEST_F(RenderTest, RayTracedBodiesShadowTheGroundUnderThem) {
  const TwoBoxBodies boxes;
  BodyDrawInput bodies = boxes.input();
  renderer_->options().draw_ground = true;
  renderer_->options().draw_skeleton = false;
  renderer_->options().backend = RenderBackend::RayTraced;
  renderer_->options().to_sun = {0.0f, 1.0f, 0.0f};
  OrbitCamera camera = figure_camera();
  camera.target = {0.0f, 0.3f, 0.0f};
  camera.pitch = 0.7f;
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  renderer_->render(SkeletonDrawInput{}, view, projection, &bodies);
  std::vector<std::uint8_t> image;
  renderer_->read_rgba(image);
  const Pixel under = project({-0.6f, 0.0f, 0.0f}, view, projection), open = project({-0.6f, 0.0f, 1.0f}, view, projection);
  EXPECT_LT(luminance(pixel_at(image, static_cast<int>(under.x), static_cast<int>(under.y))) /
                luminance(pixel_at(image, static_cast<int>(open.x), static_cast<int>(open.y))),
            0.75f);
}

// Impostors are refused before any work; a walker with a non-finite vertex is left out of the frame while the
// other is traced; the same frame gives the same bytes on one thread and on two, and again on a second call
// (the scene then refits instead of building), and after a walker left the batch and came back.
TEST_F(RenderTest, RayTracerRefusesImpostorsSkipsNonFiniteWalkersAndIsDeterministic) {
  renderer_->options().backend = RenderBackend::RayTraced;
  renderer_->options().draw_skeleton = false;
  const OrbitCamera camera = figure_camera();
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  ImpostorAtlas atlas;
  const float zero = 0.0f;
  ImpostorBatch impostors;
  impostors.atlas = &atlas;
  impostors.x = impostors.y = impostors.z = impostors.heading = impostors.scale = impostors.phase = &zero;
  impostors.walker_count = 1;
  const BodyBatch batch = impostors;
  EXPECT_THROW(renderer_->render(SkeletonDrawInput{}, view, projection, BodyBatches(std::span<const BodyBatch>(&batch, 1))),
               std::invalid_argument);

  TwoBoxBodies boxes;
  auto traced = [&](const TwoBoxBodies& b) {
    BodyDrawInput in = b.input();
    renderer_->render(SkeletonDrawInput{}, view, projection, &in);
    std::vector<std::uint8_t> image;
    renderer_->read_rgba(image);
    return image;
  };
  const std::vector<std::uint8_t> first = traced(boxes), again = traced(boxes);
  EXPECT_EQ(first, again);
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    EXPECT_EQ(traced(boxes), first);
  }
  const Pixel box0 = project({-0.6f, 1.0f, 0.2f}, view, projection), box1 = project({0.6f, 0.75f, 0.2f}, view, projection);
  boxes.soa[1][boxes.per_walker + 3] = std::numeric_limits<float>::quiet_NaN();  // walker 1's y of vertex 3
  const std::vector<std::uint8_t> holed = traced(boxes);
  const Rgba sky = pixel_at(holed, 0, 0);  // the clear colour as the tracer rounds it (GL may round it apart)
  EXPECT_NE(pixel_at(holed, static_cast<int>(box0.x), static_cast<int>(box0.y)), sky);
  EXPECT_EQ(pixel_at(holed, static_cast<int>(box1.x), static_cast<int>(box1.y)), sky);
  boxes.soa[1][boxes.per_walker + 3] = 0.3f;
  EXPECT_NE(pixel_at(traced(boxes), static_cast<int>(box1.x), static_cast<int>(box1.y)), sky) << "back next frame";
  // A walker leaving the batch (culled, arrived) and coming back: the scene keeps up without a rebuild.
  BodyDrawInput one = boxes.input();
  one.walker_count = 1;
  renderer_->render(SkeletonDrawInput{}, view, projection, &one);
  std::vector<std::uint8_t> alone;
  renderer_->read_rgba(alone);
  EXPECT_NE(pixel_at(alone, static_cast<int>(box0.x), static_cast<int>(box0.y)), sky);
  EXPECT_EQ(pixel_at(alone, static_cast<int>(box1.x), static_cast<int>(box1.y)), sky);
  EXPECT_EQ(renderer_->triangles_drawn(), boxes.triangles.size() / 3);
  EXPECT_EQ(traced(boxes), first) << "both again, as at first";
}

TEST_F(RenderTest, PassesAreTimedWhenAProfilerIsSet) {
  const TwoBoxBodies boxes;
  BodyDrawInput bodies = boxes.input();
  renderer_->options().quality = RenderQuality::High;
  Profiler profiler(10, true);
  renderer_->set_profiler(&profiler);
  const OrbitCamera camera = figure_camera();
  profiler.begin_frame();
  renderer_->render(SkeletonDrawInput{}, camera.view(), camera.projection(kAspect), &bodies);
  profiler.end_frame();
  std::set<std::string> names;
  for (const SystemStats& s : profiler.stats()) names.insert(s.name);
  for (const char* pass : {"shadow_map", "ground", "skeletons", "bodies", "resolve"}) EXPECT_TRUE(names.count(pass)) << pass;
  const std::size_t events = profiler.events().size();
  renderer_->set_profiler(nullptr);
  renderer_->render(SkeletonDrawInput{}, camera.view(), camera.projection(kAspect), &bodies);
  EXPECT_EQ(profiler.events().size(), events);
}

TEST_F(RenderTest, SameInputGivesIdenticalPixels) {
  const OrbitCamera camera = figure_camera();
  renderer_->options().draw_ground = true;  // include the grid shader's derivatives
  const std::vector<std::uint8_t> first = render(skeleton_.centers, 1, camera);
  const std::vector<glm::vec3> other = translated(skeleton_.centers, {0.3f, 0.0f, 0.0f});
  render(other, 1, camera);  // something different in between
  const std::vector<std::uint8_t> second = render(skeleton_.centers, 1, camera);
  EXPECT_TRUE(first == second);

  RenderOptions options = options_;
  options.draw_ground = true;
  CrowdRenderer fresh(kWidth, kHeight, options);
  SkeletonDrawInput input{&skeleton_, skeleton_.centers, 1};
  fresh.render(input, camera.view(), camera.projection(kAspect));
  std::vector<std::uint8_t> third;
  fresh.read_rgba(third);
  EXPECT_TRUE(first == third);
}

TEST_F(RenderTest, GroundFillsTheLowerHalf) {
  renderer_->options().draw_ground = true;
  const std::vector<std::uint8_t> image = render({}, 0, figure_camera());
  // The camera looks down on the plane y = 0 below its target: the bottom row is ground, the top row sky.
  EXPECT_TRUE(is_background(image, kWidth / 2, 0));
  EXPECT_FALSE(is_background(image, kWidth / 2, kHeight - 1));
}

TEST_F(RenderTest, CoincidentJointAddsNothingAndBreaksNothing) {
  // A zero-length bone (child on top of its parent) must not produce NaN geometry: the frame must be exactly
  // the frame without that joint.
  const OrbitCamera camera = figure_camera();
  const std::vector<std::uint8_t> reference = render(skeleton_.centers, 1, camera);
  Skeleton with_extra = skeleton_;
  with_extra.joint_names.push_back("l_ankle_copy");
  with_extra.source_joint_names.push_back("l_ankle_copy");
  with_extra.parents.push_back(12);
  with_extra.centers.push_back(skeleton_.centers[12]);
  SkeletonDrawInput input{&with_extra, with_extra.centers, 1};
  renderer_->render(input, camera.view(), camera.projection(kAspect));
  std::vector<std::uint8_t> image;
  renderer_->read_rgba(image);
  EXPECT_TRUE(image == reference);
}

TEST_F(RenderTest, RejectsTooFewJointPositions) {
  std::vector<glm::vec3> positions = skeleton_.centers;
  SkeletonDrawInput input{&skeleton_, positions, 2};
  const OrbitCamera camera;
  EXPECT_THROW(renderer_->render(input, camera.view(), camera.projection(kAspect)), std::invalid_argument);
}

TEST_F(RenderTest, ResizeChangesTheImageSize) {
  renderer_->resize(64, 32);
  EXPECT_EQ(renderer_->width(), 64);
  EXPECT_EQ(renderer_->height(), 32);
  SkeletonDrawInput input{&skeleton_, skeleton_.centers, 1};
  const OrbitCamera camera = figure_camera();
  renderer_->render(input, camera.view(), camera.projection(2.0f));
  std::vector<std::uint8_t> image;
  renderer_->read_rgba(image);
  EXPECT_EQ(image.size(), 64u * 32u * 4u);
}

// ---- body sources, the reference pass, shaders ------------------------------------------------------------

// A source other than CpuSkinnedBodies: the renderer must draw whatever a BodySource hands out, batch by batch.
class ListedBodies final : public BodySource {
 public:
  explicit ListedBodies(std::vector<BodyDrawInput> batches) : batches_(std::move(batches)) {}
  std::size_t batch_count() const override { return batches_.size(); }
  BodyBatch batch(std::size_t index) const override { return batches_[index]; }

 private:
  std::vector<BodyDrawInput> batches_;
};

TEST_F(RenderTest, EveryBodyOverloadDrawsTheSamePixels) {
  const TwoBoxBodies boxes;
  renderer_->options().draw_skeleton = false;
  const OrbitCamera camera = figure_camera();
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  const BodyDrawInput bodies = boxes.input();
  const auto frame = [&](auto&& draw) {
    draw();
    std::vector<std::uint8_t> image;
    renderer_->read_rgba(image);
    return image;
  };
  const auto by_pointer = frame([&] { renderer_->render(SkeletonDrawInput{}, view, projection, &bodies); });
  EXPECT_EQ(renderer_->triangles_drawn(), 2u * 12u);
  const auto by_span = frame([&] {
    renderer_->render(SkeletonDrawInput{}, view, projection, std::span<const BodyDrawInput>(&bodies, 1));
  });
  const auto by_source = frame([&] {
    const CpuSkinnedBodies source(std::span<const BodyDrawInput>(&bodies, 1));
    renderer_->render(SkeletonDrawInput{}, view, projection, source);
  });
  // The same two walkers as two batches of one walker each (walker 1's block starts `stride` floats later).
  BodyDrawInput first = bodies, second = bodies;
  first.walker_count = second.walker_count = 1;
  for (const float** a : {&second.px, &second.py, &second.pz, &second.nx, &second.ny, &second.nz}) *a += bodies.stride;
  const auto by_batches = frame([&] {
    renderer_->render(SkeletonDrawInput{}, view, projection, ListedBodies({first, second}));
  });
  EXPECT_EQ(renderer_->triangles_drawn(), 2u * 12u);
  EXPECT_TRUE(by_pointer == by_span);
  EXPECT_TRUE(by_pointer == by_source);
  EXPECT_TRUE(by_pointer == by_batches);
  EXPECT_FALSE(by_pointer == frame([&] { renderer_->render(SkeletonDrawInput{}, view, projection); }));
}

TEST_F(RenderTest, MoreBodyBatchesThanSlotsAreRejectedBeforeDrawing) {
  const TwoBoxBodies boxes;
  const OrbitCamera camera = figure_camera();
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  const std::vector<BodyDrawInput> four(BodyPass::kMaxBatches, boxes.input());
  renderer_->render(SkeletonDrawInput{}, view, projection, four);
  EXPECT_EQ(renderer_->triangles_drawn(), 4u * 2u * 12u);
  std::vector<std::uint8_t> before, after;
  renderer_->read_rgba(before);
  const std::vector<BodyDrawInput> five(BodyPass::kMaxBatches + 1, boxes.input());
  const std::vector<glm::vec3> figure = skeleton_.centers;
  EXPECT_THROW(renderer_->render(SkeletonDrawInput{&skeleton_, figure, 1}, view, projection, five),
               std::invalid_argument);
  renderer_->read_rgba(after);
  EXPECT_TRUE(before == after) << "a rejected frame must leave the last image as it was";
}

// The benchmark's reference draws walker 0's mesh at each offset with the body pass's shaders and material: one
// copy at offset zero is exactly the body pass drawing walker 0 alone.
TEST_F(RenderTest, InstancedReferenceAtOffsetZeroMatchesTheBodyPass) {
  const TwoBoxBodies boxes;
  renderer_->options().draw_skeleton = false;
  const OrbitCamera camera = figure_camera();
  const glm::mat4 view = camera.view(), projection = camera.projection(kAspect);
  BodyDrawInput walker0 = boxes.input();
  walker0.walker_count = 1;
  renderer_->render(SkeletonDrawInput{}, view, projection, &walker0);
  std::vector<std::uint8_t> body, reference, moved;
  renderer_->read_rgba(body);
  const std::vector<glm::vec3> at_origin{glm::vec3(0.0f)};
  renderer_->render_instanced_reference(boxes.input(), at_origin, view, projection);
  EXPECT_EQ(renderer_->triangles_drawn(), 12u);
  renderer_->read_rgba(reference);
  EXPECT_TRUE(body == reference);
  const std::vector<glm::vec3> two{glm::vec3(0.0f), glm::vec3(0.9f, 0.0f, 0.0f)};
  renderer_->render_instanced_reference(boxes.input(), two, view, projection);
  EXPECT_EQ(renderer_->triangles_drawn(), 24u);
  renderer_->read_rgba(moved);
  EXPECT_FALSE(moved == reference);
  BodyDrawInput none;
  EXPECT_THROW(renderer_->render_instanced_reference(none, two, view, projection), std::invalid_argument);
}

TEST(GroundExtent, CentresUnderThePointsAndReachesPastThem) {
  const GroundExtent empty = ground_extent({});
  EXPECT_EQ(empty.center, glm::vec2(0.0f));
  EXPECT_EQ(empty.half_size, 25.0f);
  const float nan = std::nanf("");
  const std::vector<glm::vec3> points{{-40.0f, 1.0f, 2.0f}, {40.0f, 0.0f, 6.0f}, {nan, 0.0f, 100.0f}};
  const GroundExtent e = ground_extent(points);
  EXPECT_EQ(e.center, glm::vec2(0.0f, 4.0f));
  // The farthest point is a corner of the 80 x 4 m box, 40.05 m from the centre: the ground reaches 40 % further.
  const float reach = std::sqrt(40.0f * 40.0f + 2.0f * 2.0f);
  EXPECT_FLOAT_EQ(e.half_size, 1.4f * reach);
  EXPECT_FLOAT_EQ(e.fade_start, reach + 2.0f) << "no point stands on faded ground";
  EXPECT_FLOAT_EQ(empty.fade_start, 15.0f);
  // A small crowd keeps the 25 m ground and its fade from 15 m.
  const std::vector<glm::vec3> near{{-3.0f, 0.0f, -3.0f}, {3.0f, 0.0f, 3.0f}};
  EXPECT_EQ(ground_extent(near).half_size, 25.0f);
  EXPECT_FLOAT_EQ(ground_extent(near).fade_start, 15.0f);
}

// Every shader the passes load is embedded in the library (the program runs with no file beside it).
// screen_footprint (render/footprint.h): every point of a box, and of the segment from it to its shadow on the
// ground, that lies in front of the near plane projects inside the rectangle, for a camera outside the box and one
// standing inside its extent (the box reaching behind it), where the rectangle is still not the whole frame.
// Degenerate inputs: an empty box gives nothing, a NaN or a sun at the horizon the whole frame.
TEST(ScreenFootprint, HoldsEveryVisiblePointOfTheBoxAndItsShadow) {
  const int width = 320, height = 180;
  const glm::vec3 to_sun = glm::normalize(glm::vec3(-0.6f, 0.6f, 0.4f));
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  struct Case {
    glm::vec3 lo, hi, eye, target;
  };
  const Case cases[] = {
      {{-2.0f, 0.0f, -3.0f}, {3.0f, 2.0f, 1.0f}, {0.0f, 4.0f, 14.0f}, {0.0f, 0.5f, 0.0f}},    // outside
      {{-6.0f, 0.0f, -20.0f}, {6.0f, 1.0f, 6.0f}, {0.0f, 3.0f, 3.0f}, {4.0f, 0.0f, -10.0f}},  // above, inside its extent
  };
  for (const Case& c : cases) {
    const glm::mat4 vp = glm::perspective(0.8f, float(width) / height, 0.1f, 500.0f) * glm::lookAt(c.eye, c.target, {0.0f, 1.0f, 0.0f});
    for (const glm::vec3* sun : {static_cast<const glm::vec3*>(nullptr), &to_sun}) {
      const PixelRect r = screen_footprint(c.lo, c.hi, sun, vp, width, height, 0);
      ASSERT_FALSE(r.empty());
      EXPECT_LT(double(r.x1 - r.x0) * (r.y1 - r.y0), 0.9 * width * height) << "a rectangle, not the whole frame";
      std::size_t seen = 0;
      for (int k = 0; k < 20000; ++k) {
        glm::vec3 p = glm::mix(c.lo, c.hi, glm::vec3(unit(rng), unit(rng), unit(rng)));
        if (sun) p -= *sun * (unit(rng) * p.y / sun->y);  // somewhere on its way down to its shadow
        const glm::vec4 q = vp * glm::vec4(p, 1.0f);
        if (q.z < -q.w) continue;  // behind the near plane: not drawn
        const float x = (q.x / q.w + 1.0f) * 0.5f * width, y = (1.0f - q.y / q.w) * 0.5f * height;
        if (x < 0.0f || y < 0.0f || x >= width || y >= height) continue;  // off screen
        ++seen;
        ASSERT_TRUE(r.contains(int(std::floor(x)), int(std::floor(y)))) << x << ", " << y;
      }
      EXPECT_GT(seen, 1000u);
    }
  }
  const glm::mat4 vp = glm::perspective(0.8f, 1.0f, 0.1f, 100.0f) * glm::lookAt(glm::vec3(0, 2, 10), glm::vec3(0), glm::vec3(0, 1, 0));
  EXPECT_TRUE(screen_footprint(glm::vec3(1.0f), glm::vec3(-1.0f), nullptr, vp, 64, 64).empty());
  EXPECT_TRUE(screen_footprint({-1, 0, 20}, {1, 1, 30}, nullptr, vp, 64, 64).empty()) << "wholly behind the camera";
  EXPECT_EQ(screen_footprint({NAN, 0, 0}, {1, 1, 1}, nullptr, vp, 64, 64), (PixelRect{0, 0, 64, 64}));
  const glm::vec3 low_sun(1.0f, 0.01f, 0.0f);
  EXPECT_EQ(screen_footprint({-1, 0, -1}, {1, 2, 1}, &low_sun, vp, 64, 64), (PixelRect{0, 0, 64, 64}));
}

TEST(Shaders, EveryPassShaderIsEmbedded) {
  for (const char* path : {"render/shaders/skeleton.vert", "render/shaders/lit.frag", "render/shaders/body.vert",
                           "render/shaders/ground.vert", "render/shaders/ground.frag"}) {
    const std::string_view text = shader_source(path);
    EXPECT_EQ(text.substr(0, 17), "#version 450 core") << path;
  }
  try {
    (void)shader_source("render/shaders/missing.vert");
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("render/shaders/missing.vert"), std::string::npos) << e.what();
  }
}

TEST(Shaders, CompileAndLinkErrorsNameTheShaderFiles) {
  std::unique_ptr<GlContext> context;
  try {
    context = create_headless_gl_context();
  } catch (const std::exception& e) {
    FAIL() << e.what();
  }
  const auto message = [](auto&& link) {
    try {
      link();
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  const std::string_view vert = shader_source("render/shaders/body.vert");
  const std::string_view frag = shader_source("render/shaders/lit.frag");
  EXPECT_NO_THROW(link_program("render/shaders/body.vert", vert, "render/shaders/lit.frag", frag));
  const std::string broken_vert = message([&] {
    link_program("render/shaders/broken.vert", "#version 450 core\nvoid main() { oops }\n", "lit.frag", frag);
  });
  EXPECT_EQ(broken_vert.rfind("render/shaders/broken.vert: failed to compile: ", 0), 0u) << broken_vert;
  const std::string broken_frag = message(
      [&] { link_program("body.vert", vert, "render/shaders/broken.frag", "#version 450 core\nvoid main() {\n"); });
  EXPECT_EQ(broken_frag.rfind("render/shaders/broken.frag: failed to compile: ", 0), 0u) << broken_frag;
  // Each stage compiles alone; the fragment stage reads an input no vertex stage writes, which only the link sees.
  const std::string unlinked = message([&] {
    link_program("render/shaders/a.vert", "#version 450 core\nvoid main() { gl_Position = vec4(0.0); }\n",
                 "render/shaders/b.frag",
                 "#version 450 core\nin vec3 v_missing;\nout vec4 f;\nvoid main() { f = vec4(v_missing, 1.0); }\n");
  });
  EXPECT_EQ(unlinked.rfind("render/shaders/a.vert + render/shaders/b.frag: failed to link: ", 0), 0u) << unlinked;
}

// ---- bone_transform ---------------------------------------------------------------------------------------

TEST(BoneTransform, MapsTheUnitBoneOntoTheSegmentWithAnOrthogonalRightHandedBasis) {
  const glm::vec3 a{0.3f, 1.2f, -0.4f};
  const float radius = 0.05f;
  // Axis-aligned directions hit any fixed helper axis; the others are generic.
  const glm::vec3 directions[] = {{0, 1, 0},  {0, -1, 0},       {1, 0, 0},          {0, 0, -1},
                                  {1, 1, 1},  {-0.2f, 0.9f, 0.1f}, {0.7f, -0.1f, -0.7f}, {1e-4f, 1.0f, -1e-4f}};
  for (const glm::vec3& dir : directions) {
    const glm::vec3 b = a + 0.37f * glm::normalize(dir);
    const auto m = bone_transform(a, b, radius);
    ASSERT_TRUE(m.has_value());
    const glm::vec3 start = glm::vec3(*m * glm::vec4(0, 0, 0, 1));
    const glm::vec3 end = glm::vec3(*m * glm::vec4(0, 1, 0, 1));
    EXPECT_LT(glm::length(start - a), 1e-6f);
    EXPECT_LT(glm::length(end - b), 1e-5f);
    const glm::vec3 c0{(*m)[0]}, c1{(*m)[1]}, c2{(*m)[2]};
    EXPECT_NEAR(glm::length(c0), radius, 1e-6f);
    EXPECT_NEAR(glm::length(c2), radius, 1e-6f);
    EXPECT_NEAR(glm::dot(c0, c1), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::dot(c1, c2), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::dot(c0, c2), 0.0f, 1e-6f);
    EXPECT_GT(glm::dot(c0, glm::cross(c1, c2)), 0.0f) << "left-handed basis flips the winding";
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 4; ++k) EXPECT_TRUE(std::isfinite((*m)[i][k]));
  }
}

TEST(BoneTransform, RejectsZeroLengthAndNonFiniteBones) {
  const glm::vec3 a{1.0f, 2.0f, 3.0f};
  EXPECT_FALSE(bone_transform(a, a, 0.02f).has_value());
  EXPECT_FALSE(bone_transform(a, glm::vec3{NAN, 0.0f, 0.0f}, 0.02f).has_value());
  EXPECT_FALSE(bone_transform(glm::vec3{INFINITY, 0.0f, 0.0f}, a, 0.02f).has_value());
}

// ---- camera ---------------------------------------------------------------------------------------------

TEST(OrbitCamera, YawZeroLooksAlongMinusZAndPositiveYawSwingsTowardsPlusX) {
  OrbitCamera camera;
  camera.target = {1.0f, 2.0f, 3.0f};
  camera.distance = 5.0f;
  camera.yaw = 0.0f;
  camera.pitch = 0.0f;
  EXPECT_LT(glm::length(camera.eye() - glm::vec3{1.0f, 2.0f, 8.0f}), 1e-5f);
  const glm::vec4 target_in_view = camera.view() * glm::vec4(camera.target, 1.0f);
  EXPECT_LT(glm::length(glm::vec3(target_in_view) - glm::vec3{0.0f, 0.0f, -5.0f}), 1e-5f);
  camera.yaw = 1.5707963f;
  EXPECT_LT(glm::length(camera.eye() - glm::vec3{6.0f, 2.0f, 3.0f}), 1e-5f);
  camera.yaw = 0.0f;
  camera.pitch = 0.5f;
  EXPECT_NEAR(camera.eye().y, 2.0f + 5.0f * std::sin(0.5f), 1e-5f);
}

TEST(OrbitCamera, FrameBoxFitsTheBoundingSphereInBothFieldsOfView) {
  const glm::vec3 lo{-4.0f, 0.0f, -2.0f}, hi{6.0f, 1.8f, 3.0f};
  const glm::vec3 center = 0.5f * (lo + hi);
  const float radius = 0.5f * glm::length(hi - lo);
  for (float aspect : {0.5f, 1.0f, 4.0f / 3.0f, 2.5f})
    for (float yaw : {0.0f, 0.7f, -2.0f})
      for (float pitch : {0.1f, 0.6f, 1.2f}) {
        OrbitCamera camera;
        camera.yaw = yaw;
        camera.pitch = pitch;
        camera.frame_box(lo, hi, aspect);
        const glm::mat4 vp = camera.projection(aspect) * camera.view();
        // Points spread over the bounding sphere (Fibonacci lattice): all must be in view, and the sphere must
        // touch the edge of the narrower field of view (x when the image is taller than wide, y otherwise).
        float reach = 0.0f;
        constexpr int kSamples = 4000;
        for (int i = 0; i < kSamples; ++i) {
          const float y = 1.0f - 2.0f * (static_cast<float>(i) + 0.5f) / kSamples;
          const float ring = std::sqrt(1.0f - y * y), phi = 2.39996323f * static_cast<float>(i);
          const glm::vec3 p = center + radius * glm::vec3{ring * std::cos(phi), y, ring * std::sin(phi)};
          const glm::vec4 clip = vp * glm::vec4(p, 1.0f);
          ASSERT_GT(clip.w, 0.0f);
          const glm::vec3 ndc = glm::vec3(clip) / clip.w;
          ASSERT_LE(std::abs(ndc.x), 1.0f + 1e-4f) << aspect << " " << yaw << " " << pitch;
          ASSERT_LE(std::abs(ndc.y), 1.0f + 1e-4f) << aspect << " " << yaw << " " << pitch;
          ASSERT_GT(ndc.z, -1.0f);
          ASSERT_LT(ndc.z, 1.0f);
          reach = std::max(reach, aspect < 1.0f ? std::abs(ndc.x) : std::abs(ndc.y));
        }
        EXPECT_GT(reach, 0.98f) << "sphere framed loosely: " << aspect << " " << yaw << " " << pitch;
      }
}

TEST(OrbitCamera, FrameBoxTightPutsTheOutermostCornerOnTheMargin) {
  const glm::vec3 lo{-4.0f, 0.0f, -2.0f}, hi{6.0f, 1.8f, 3.0f};
  for (float aspect : {0.5f, 16.0f / 9.0f})
    for (float yaw : {0.0f, 0.7f, -2.0f})
      for (float pitch : {0.1f, 0.6f, 1.2f}) {
        OrbitCamera camera;
        camera.yaw = yaw;
        camera.pitch = pitch;
        const float margin = 1.1f;
        camera.frame_box_tight(lo, hi, aspect, margin);
        const glm::mat4 vp = camera.projection(aspect) * camera.view();
        float reach = 0.0f;
        for (int i = 0; i < 8; ++i) {
          const glm::vec3 corner{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z};
          const glm::vec4 clip = vp * glm::vec4(corner, 1.0f);
          ASSERT_GT(clip.w, 0.0f);
          const glm::vec3 ndc = glm::vec3(clip) / clip.w;
          reach = std::max({reach, std::abs(ndc.x), std::abs(ndc.y)});
          ASSERT_GT(ndc.z, -1.0f);
          ASSERT_LT(ndc.z, 1.0f);
        }
        EXPECT_NEAR(reach, 1.0f / margin, 1e-3f) << aspect << " " << yaw << " " << pitch;
        OrbitCamera touching = camera, sphere = camera;
        touching.frame_box_tight(lo, hi, aspect, 1.0f);
        sphere.frame_box(lo, hi, aspect);
        EXPECT_LE(touching.distance, sphere.distance + 1e-4f) << "without margin, never looser than the sphere fit";
      }
}

TEST(OrbitCamera, PanKeepsThePointUnderTheCursor) {
  OrbitCamera camera;
  const float height = 600.0f, aspect = 1.5f, width = height * aspect;
  const glm::vec3 anchor = camera.target;
  camera.pan(40.0f, -25.0f, height);
  const glm::vec4 clip = camera.projection(aspect) * camera.view() * glm::vec4(anchor, 1.0f);
  const float x = (clip.x / clip.w * 0.5f + 0.5f) * width;
  const float y = (0.5f - clip.y / clip.w * 0.5f) * height;
  EXPECT_NEAR(x, 0.5f * width + 40.0f, 0.05f);
  EXPECT_NEAR(y, 0.5f * height - 25.0f, 0.05f);
}

TEST(OrbitCamera, OrbitDragsAndZoom) {
  OrbitCamera camera;
  camera.yaw = 0.0f;
  camera.pitch = 0.0f;
  camera.orbit(150.0f, 0.0f, 300.0f);  // half the height to the right: a quarter turn, eye to -X
  EXPECT_NEAR(camera.eye().x - camera.target.x, -camera.distance, 1e-4f);
  camera.orbit(0.0f, 1e4f, 300.0f);  // far down: the pitch clamps below the pole
  EXPECT_NEAR(camera.pitch, 1.5f, 1e-6f);
  const float before = camera.distance;
  camera.zoom(2.0f);
  EXPECT_LT(camera.distance, before);
  camera.zoom(-2.0f);
  EXPECT_NEAR(camera.distance, before, 1e-4f);
}

TEST(WindowInput, AppliesDragsAndScrollToTheCamera) {
  OrbitCamera camera, reference;
  apply_camera_input(WindowInput{}, 500.0f, camera);
  EXPECT_EQ(camera.yaw, reference.yaw);
  EXPECT_EQ(camera.distance, reference.distance);
  WindowInput input;
  input.orbit_drag = {10.0f, 0.0f};
  input.scroll = 1.0f;
  apply_camera_input(input, 500.0f, camera);
  reference.orbit(10.0f, 0.0f, 500.0f);
  reference.zoom(1.0f);
  EXPECT_FLOAT_EQ(camera.yaw, reference.yaw);
  EXPECT_FLOAT_EQ(camera.distance, reference.distance);
}

// Needs an X display (xvfb-run -a); skipped otherwise because GLFW 3.3 has no headless platform.
TEST(GlfwWindow, HiddenWindowRendersAndBlits) {
  if (std::getenv("DISPLAY") == nullptr) GTEST_SKIP() << "no DISPLAY";
  WindowOptions options;
  options.width = 160;
  options.height = 120;
  options.visible = false;
  GlfwWindow window(options);
  const std::string version = window.version();
  int major = 0, minor = 0;
  ASSERT_EQ(std::sscanf(version.c_str(), "%d.%d", &major, &minor), 2) << version;
  EXPECT_TRUE(major > 4 || (major == 4 && minor >= 5)) << version;
  const glm::ivec2 fb = window.framebuffer_size();
  ASSERT_GT(fb.x, 0);
  CrowdRenderer renderer(fb.x, fb.y);
  const Skeleton skeleton = make_stick_figure();
  SkeletonDrawInput input{&skeleton, skeleton.centers, 1};
  const OrbitCamera camera = figure_camera();
  renderer.render(input, camera.view(), camera.projection(static_cast<float>(fb.x) / fb.y));
  renderer.blit_to_default_framebuffer(fb.x, fb.y);
  window.swap_buffers();
  const WindowInput events = window.poll_events();
  EXPECT_FALSE(events.quit);
  window.request_close();
  EXPECT_TRUE(window.should_close());
}

// ---- PNG writing ------------------------------------------------------------------------------------------

class PngTest : public ::testing::Test {
 protected:
  static std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  static std::uint32_t big_endian(const std::vector<std::uint8_t>& b, std::size_t at) {
    return (std::uint32_t{b[at]} << 24) | (std::uint32_t{b[at + 1]} << 16) | (std::uint32_t{b[at + 2]} << 8) |
           std::uint32_t{b[at + 3]};
  }

  const test::TempDir tmp_{"strata_render_test"};  // a scratch directory per test, removed afterwards
  const std::filesystem::path& dir_ = tmp_.path();
};

TEST_F(PngTest, WritesAValidPngHeaderForRgbaAndRgb) {
  const int width = 37, height = 21;  // odd sizes catch stride mistakes in the header
  for (int channels : {4, 3}) {
    std::vector<std::uint8_t> pixels(static_cast<std::size_t>(width * height * channels));
    for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<std::uint8_t>(i * 7);
    const std::filesystem::path path = dir_ / ("image" + std::to_string(channels) + ".png");
    write_image(path, width, height, channels, pixels);
    const std::vector<std::uint8_t> bytes = read_bytes(path);
    ASSERT_GE(bytes.size(), 33u);
    const std::uint8_t signature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    for (std::size_t i = 0; i < 8; ++i) EXPECT_EQ(bytes[i], signature[i]) << "signature byte " << i;
    EXPECT_EQ(big_endian(bytes, 8), 13u);  // IHDR length
    EXPECT_EQ(std::string(bytes.begin() + 12, bytes.begin() + 16), "IHDR");
    EXPECT_EQ(big_endian(bytes, 16), static_cast<std::uint32_t>(width));
    EXPECT_EQ(big_endian(bytes, 20), static_cast<std::uint32_t>(height));
    EXPECT_EQ(bytes[24], 8);                         // bit depth
    EXPECT_EQ(bytes[25], channels == 4 ? 6 : 2);     // colour type: RGBA / RGB
  }
}

TEST_F(PngTest, WritesARenderedFrame) {
  std::unique_ptr<GlContext> context;
  try {
    context = create_headless_gl_context();
  } catch (const std::exception& e) {
    FAIL() << e.what();
  }
  CrowdRenderer renderer(kWidth, kHeight);
  const Skeleton skeleton = make_stick_figure();
  const OrbitCamera camera = figure_camera();
  renderer.render({&skeleton, skeleton.centers, 1}, camera.view(), camera.projection(kAspect));
  std::vector<std::uint8_t> pixels;
  renderer.read_rgba(pixels);
  const std::filesystem::path path = dir_ / "frame.png";
  write_image(path, kWidth, kHeight, 4, pixels);
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  ASSERT_GE(bytes.size(), 33u);
  EXPECT_EQ(big_endian(bytes, 16), static_cast<std::uint32_t>(kWidth));
  EXPECT_EQ(big_endian(bytes, 20), static_cast<std::uint32_t>(kHeight));
}

TEST_F(PngTest, MissingDirectoryIsAnErrorNamingThePath) {
  const std::filesystem::path path = dir_ / "no_such_dir" / "frame.png";
  const std::vector<std::uint8_t> pixels(4 * 4 * 4, 0);
  try {
    write_image(path, 4, 4, 4, pixels);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST_F(PngTest, RejectsAPixelBufferOfTheWrongSize) {
  const std::filesystem::path path = dir_ / "short.png";
  const std::vector<std::uint8_t> pixels(4 * 4 * 3, 0);
  EXPECT_THROW(write_image(path, 4, 4, 4, pixels), std::runtime_error);
  EXPECT_THROW(write_image(path, 4, 4, 2, pixels), std::runtime_error);
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace strata
