// Impostors on a real headless GL (Mesa llvmpipe through EGL): the baked atlas holds the walker in every cell with
// unit normals; an impostor drawn where a mesh walker stood looks like it; impostors sort by their baked depth
// whatever order they are drawn in; a malformed batch is refused before the frame starts; a frame's footprint
// (render/footprint.h) holds every pixel its walkers, meshes or impostors, and their shadows change.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "io/hanim_loader.h"
#include "render/crowd_renderer.h"
#include "render/footprint.h"
#include "render/gl_context.h"
#include "render/impostor_bake.h"
#include "render/scene_draw.h"
#include "rig/body_rig.h"
#include "rig/muscle_binding.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/step.h"

namespace strata {
namespace {

Rig default_rig() {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  rig.muscles = default_muscle_rig();
  return rig;
}

// Fewer phases and elevations than the default, for a bake of a second or two: rows at 0, 30 and 60 degrees.
ImpostorBakeOptions small_bake() {
  ImpostorBakeOptions o;
  o.layout.phases = 8;
  o.layout.azimuths = 16;
  o.layout.elevations = 3;
  o.layout.max_elevation_deg = 60.0f;
  return o;
}

class ImpostorTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    try {
      context_ = create_headless_gl_context().release();
    } catch (const std::exception& e) {
      context_ = nullptr;
      return;
    }
    atlas_ = new ImpostorAtlas(bake_impostor_atlas(default_rig(), GaitStyle{}, small_bake()));
  }
  static void TearDownTestSuite() {
    delete atlas_;
    delete context_;
    atlas_ = nullptr, context_ = nullptr;
  }
  void SetUp() override {
    if (!context_) GTEST_SKIP() << "no headless GL";
  }
  static GlContext* context_;
  static ImpostorAtlas* atlas_;
};
GlContext* ImpostorTest::context_ = nullptr;
ImpostorAtlas* ImpostorTest::atlas_ = nullptr;

// The colour image holds dress weights (components/impostor_atlas.h): fully covered texels of the shirt, the
// trousers and the hair, and of bare skin (no weight), all present in the front view at heel strike; no texel
// weighs more than one in all.
TEST_F(ImpostorTest, TheAtlasHoldsEachTexelsDressWeights) {
  const ImpostorAtlas& a = *atlas_;
  const ImpostorAtlasLayout& l = a.layout;
  std::size_t top = 0, bottom = 0, hair = 0, skin = 0, overweight = 0;
  for (int y = 0; y < l.cell_height; ++y)
    for (int x = 0; x < l.cell_width; ++x) {
      const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(l.layer_width()) + static_cast<std::size_t>(x)) * 4;
      if (a.color[i + 3] != 255) continue;
      const int r = a.color[i], g = a.color[i + 1], b = a.color[i + 2];
      top += r > 240, bottom += g > 240, hair += b > 240, skin += r + g + b < 15;
      overweight += r + g + b > 255 + 3;
    }
  EXPECT_GT(top, 50u);
  EXPECT_GT(bottom, 50u);
  EXPECT_GT(hair, 5u);
  EXPECT_GT(skin, 20u);
  EXPECT_EQ(overweight, 0u);
}

TEST_F(ImpostorTest, EveryCellHoldsTheWalkerWithUnitNormals) {
  const ImpostorAtlas& a = *atlas_;
  ASSERT_TRUE(a.complete());
  EXPECT_GT(a.bake_seconds, 0.0);
  const ImpostorAtlasLayout& l = a.layout;
  const int W = l.layer_width();
  std::vector<int> width_of(static_cast<std::size_t>(l.azimuths));
  std::size_t opaque = 0, unit = 0;
  for (int k = 0; k < l.phases; ++k)
    for (int e = 0; e < l.elevations; ++e)
      for (int az = 0; az < l.azimuths; ++az) {
        std::size_t covered = 0;
        int x0 = l.cell_width, x1 = -1, y0 = l.cell_height, y1 = -1;
        for (int y = 0; y < l.cell_height; ++y)
          for (int x = 0; x < l.cell_width; ++x) {
            const std::size_t i = static_cast<std::size_t>(k) * l.layer_bytes() +
                                  (static_cast<std::size_t>(e * l.cell_height + y) * W + static_cast<std::size_t>(az * l.cell_width + x)) * 4;
            if (a.color[i + 3] == 0) continue;
            ++covered;
            x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
            if (a.color[i + 3] == 255) {
              const glm::vec3 n(a.normal_depth[i] / 127.5f - 1.0f, a.normal_depth[i + 1] / 127.5f - 1.0f,
                                a.normal_depth[i + 2] / 127.5f - 1.0f);
              ++opaque;
              unit += std::abs(glm::length(n) - 1.0f) < 0.05f;
            }
          }
        ASSERT_GT(covered, static_cast<std::size_t>(l.cell_width * l.cell_height) / 20) << "phase " << k << " cell " << az << "," << e;
        // The walker never touches the cell's edge: the cell frames the whole body.
        EXPECT_GT(x0, 0);
        EXPECT_LT(x1, l.cell_width - 1);
        EXPECT_GT(y0, 0);
        EXPECT_LT(y1, l.cell_height - 1);
        if (k == 0 && e == 0) width_of[static_cast<std::size_t>(az)] = x1 - x0;
      }
  // Texels where a limb's edge crosses the body average two normals over the multisamples and come out shorter;
  // every other covered texel holds a unit normal.
  EXPECT_GT(double(unit), 0.9 * double(opaque));
  // At heel strike the legs are apart along the walk: seen from the side (azimuth 90 deg) the walker is wider
  // than seen from the front.
  EXPECT_GT(width_of[static_cast<std::size_t>(l.azimuths / 4)], width_of[0]);
}

double psnr(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  double se = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (i % 4 == 3) continue;
    const double d = double(a[i]) - double(b[i]);
    se += d * d, ++n;
  }
  return se > 0.0 ? 10.0 * std::log10(255.0 * 255.0 * double(n) / se) : 99.0;
}

// One walker about 90 px tall (just below the impostor threshold) drawn as its level-2 mesh and as an impostor,
// from the same camera at the same gait phase.
TEST_F(ImpostorTest, AnImpostorLooksLikeTheMeshItReplaces) {
  const int width = 320, height = 240;
  CrowdRenderer renderer(width, height);
  auto make = [&](DetailLevel level) {
    auto crowd = std::make_unique<Crowd>(default_rig());
    set_detail_level(*crowd, level);
    CrowdConfig config;
    config.walkers = 1;
    config.motion = MotionSource::Walk;
    spawn_crowd(*crowd, config);
    crowd->impostor_atlas = std::make_shared<const ImpostorAtlas>(*atlas_);
    return crowd;
  };
  auto mesh = make(DetailLevel::mesh(2));
  auto impostor = make(DetailLevel::impostor());
  OrbitCamera camera;
  camera.fov_y = 0.8f;
  camera.pitch = 0.1f;
  camera.yaw = 0.9f;
  const float aspect = float(width) / float(height);
  RenderScratch scratch;
  Profiler profiler(1, false);
  std::vector<std::uint8_t> a, b;
  for (int f = 0; f < 5; ++f) {
    for (Crowd* c : {mesh.get(), impostor.get()}) step(*c, 1.0f / 30.0f, profiler);
    // Follow the walker, 5.5 m away: 240 / (2 tan 0.4) * 1.75 / 5.5 = 90 px.
    const SoaTable& t = mesh->table(DetailSlot::Mesh2);
    camera.target = glm::vec3(t.f32(kWalkerPlacement, 0)[0], 0.9f, t.f32(kWalkerPlacement, 2)[0]);
    camera.distance = 5.5f;
    render_frame(*mesh, renderer, camera, aspect, height, scratch);
    renderer.read_rgba(a);
    render_frame(*impostor, renderer, camera, aspect, height, scratch);
    EXPECT_EQ(renderer.impostors_drawn(), 1u);
    renderer.read_rgba(b);
    EXPECT_GT(psnr(a, b), 30.0) << "frame " << f;
  }
  // And it is drawn: the impostor frame differs from an empty one where the walker stands.
  auto empty = make(DetailLevel::impostor());
  despawn(*empty, empty->world.entities()[0]);
  step(*empty, 1.0f / 30.0f, profiler);
  std::vector<std::uint8_t> c;
  render_frame(*empty, renderer, camera, aspect, height, scratch);
  renderer.read_rgba(c);
  EXPECT_LT(psnr(b, c), 35.0);
}

// The footprint a distributed crowd composites by (dist/composite.h): the frame of two walkers against the frame
// of the same scene without them, both fitting the ground and the sun's frustum to one shared box as the
// processes of a distributed crowd do (RenderFrameOptions::share_bounds), at high quality under a low sun (30
// degrees: shadows 1.7 times as long as a walker is tall). Every pixel that differs lies inside the footprint; some
// lie outside the walkers' own rectangle (their shadows, which the footprint must hold); and the footprint is not
// the whole frame. As meshes and as impostors, whose shadows (drawn from the atlas as seen from the sun) cover
// about as much ground as the meshes' do.
TEST_F(ImpostorTest, TheFootprintHoldsEveryPixelTheWalkersAndTheirShadowsChange) {
  const int width = 320, height = 200;
  const float aspect = float(width) / float(height);
  CrowdRenderer renderer(width, height);
  renderer.options().quality = RenderQuality::High;
  renderer.options().to_sun = {-0.75f, 0.5f, 0.43f};
  Profiler profiler(1, false);
  std::size_t shadow_pixels[2] = {0, 0};  // changed pixels beyond the walkers' rectangle: meshes, impostors
  for (const DetailLevel level : {DetailLevel::mesh(2), DetailLevel::impostor()}) {
    auto make = [&](std::size_t walkers) {
      auto crowd = std::make_unique<Crowd>(default_rig());
      set_detail_level(*crowd, level);
      CrowdConfig config;
      config.walkers = walkers;
      config.motion = MotionSource::Walk;
      spawn_crowd(*crowd, config);
      crowd->impostor_atlas = std::make_shared<const ImpostorAtlas>(*atlas_);
      for (int f = 0; f < 3; ++f) step(*crowd, 1.0f / 30.0f, profiler);
      return crowd;
    };
    const auto crowd = make(2), empty = make(0);
    // The walkers' feet, from their placements.
    glm::vec3 feet_lo(1e9f), feet_hi(-1e9f);
    for (std::size_t s = 0; s < kDetailSlots; ++s) {
      const SoaTable& t = crowd->table(static_cast<DetailSlot>(s));
      for (std::size_t row = 0; row < t.size(); ++row) {
        const glm::vec3 p(t.f32(kWalkerPlacement, 0)[row], t.f32(kWalkerPlacement, 1)[row], t.f32(kWalkerPlacement, 2)[row]);
        feet_lo = glm::min(feet_lo, p), feet_hi = glm::max(feet_hi, p);
      }
    }
    ASSERT_LE(feet_lo.x, feet_hi.x) << "the walkers stand somewhere";
    const glm::vec3 box_lo = feet_lo - glm::vec3(2.0f, 0.5f, 2.0f), box_hi = feet_hi + glm::vec3(2.0f, 2.5f, 2.0f);
    RenderFrameOptions shared;
    shared.share_bounds = [&](glm::vec3& lo, glm::vec3& hi) { lo = box_lo, hi = box_hi; };
    // Looking down at the walkers from 9 m: ground all round them.
    OrbitCamera camera;
    camera.fov_y = 0.8f;
    camera.pitch = 0.6f;
    camera.yaw = 0.4f;
    camera.target = 0.5f * (feet_lo + feet_hi) + glm::vec3(0.0f, 0.9f, 0.0f);
    camera.distance = 9.0f;
    RenderScratch scratch;
    std::vector<std::uint8_t> background, frame;
    render_frame(*empty, renderer, camera, aspect, height, scratch, shared);
    EXPECT_TRUE(renderer.last_footprint().empty()) << "no walkers, no footprint";
    renderer.read_rgba(background);
    render_frame(*crowd, renderer, camera, aspect, height, scratch, shared);
    renderer.read_rgba(frame);
    const PixelRect footprint = renderer.last_footprint();
    // The walkers' own rectangle: their feet's box up to a tall walker's height, grown by a body's reach.
    const PixelRect bodies = screen_footprint(feet_lo - glm::vec3(0.4f), feet_hi + glm::vec3(0.4f, 2.3f, 0.4f), nullptr,
                                              camera.projection(aspect) * camera.view(), width, height);
    std::size_t changed = 0, outside = 0, beyond_bodies = 0;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const std::size_t i = 4 * (static_cast<std::size_t>(y) * width + static_cast<std::size_t>(x));
        if (std::equal(&frame[i], &frame[i] + 4, &background[i])) continue;
        ++changed;
        outside += !footprint.contains(x, y);
        beyond_bodies += !bodies.contains(x, y);
      }
    const bool meshes = level.is_mesh();
    EXPECT_GT(changed, 500u) << (meshes ? "meshes" : "impostors") << ": the walkers are in the frame";
    EXPECT_EQ(outside, 0u) << (meshes ? "meshes" : "impostors") << ": footprint " << footprint.x0 << "," << footprint.y0
                           << " - " << footprint.x1 << "," << footprint.y1;
    EXPECT_GT(beyond_bodies, 50u) << (meshes ? "meshes" : "impostors") << ": shadows beyond the walkers' rectangle";
    shadow_pixels[meshes ? 0 : 1] = beyond_bodies;
    const double share = double(footprint.x1 - footprint.x0) * double(footprint.y1 - footprint.y0) / (double(width) * height);
    EXPECT_LT(share, 0.8) << (meshes ? "meshes" : "impostors");
  }
  const double ratio = double(shadow_pixels[1]) / double(std::max<std::size_t>(shadow_pixels[0], 1));
  EXPECT_GT(ratio, 0.6) << shadow_pixels[1] << " impostor shadow pixels against " << shadow_pixels[0] << " of the meshes";
  EXPECT_LT(ratio, 1.6) << shadow_pixels[1] << " impostor shadow pixels against " << shadow_pixels[0] << " of the meshes";
}

// Two impostors, one behind the other: the same image whichever is drawn first (each writes its baked depth).
TEST_F(ImpostorTest, ImpostorsSortByTheirBakedDepth) {
  const int width = 160, height = 160;
  CrowdRenderer renderer(width, height);
  renderer.options().draw_ground = false;
  const glm::mat4 projection = glm::perspective(glm::radians(40.0f), 1.0f, 0.1f, 100.0f);
  const glm::mat4 view = glm::lookAt(glm::vec3(0.0f, 1.0f, 0.0f), glm::vec3(0.0f, 1.0f, -1.0f), glm::vec3(0, 1, 0));
  auto draw = [&](bool near_first) {
    // Near walker at z = -5 facing the camera, the far one 1 m behind it and 0.25 m to the side, side-on.
    const float xs[2] = {0.0f, 0.25f}, zs[2] = {-5.0f, -6.0f}, headings[2] = {0.0f, 1.57f};
    float x[2], y[2] = {0, 0}, z[2], heading[2], scale[2] = {1, 1}, phase[2] = {0.1f, 0.6f};
    for (int i = 0; i < 2; ++i) {
      const int j = near_first ? i : 1 - i;
      x[i] = xs[j], z[i] = zs[j], heading[i] = headings[j];
      phase[i] = j == 0 ? 0.1f : 0.6f;
    }
    ImpostorBatch batch{atlas_, x, y, z, heading, scale, phase, 2};
    const std::vector<BodyBatch> batches = {batch};
    renderer.render({}, view, projection, BodyBatches(batches));
    std::vector<std::uint8_t> pixels;
    renderer.read_rgba(pixels);
    return pixels;
  };
  const std::vector<std::uint8_t> a = draw(true), b = draw(false);
  EXPECT_EQ(a, b);
  // Something is drawn in the middle (the near walker's body), unlike the clear colour in the corner.
  const std::size_t centre = (static_cast<std::size_t>(height / 2) * width + width / 2) * 4;
  EXPECT_NE(std::vector<std::uint8_t>(a.begin() + static_cast<std::ptrdiff_t>(centre), a.begin() + static_cast<std::ptrdiff_t>(centre) + 3),
            std::vector<std::uint8_t>(a.begin(), a.begin() + 3));
}

TEST_F(ImpostorTest, AMalformedBatchIsRefusedBeforeTheFrame) {
  CrowdRenderer renderer(64, 64);
  float v[1] = {0.0f};
  const glm::mat4 identity(1.0f);
  ImpostorBatch no_atlas{nullptr, v, v, v, v, v, v, 1};
  std::vector<BodyBatch> batches = {no_atlas};
  EXPECT_THROW(renderer.render({}, identity, identity, BodyBatches(batches)), std::invalid_argument);
  ImpostorBatch no_phase{atlas_, v, v, v, v, v, nullptr, 1};
  batches = {no_phase};
  EXPECT_THROW(renderer.render({}, identity, identity, BodyBatches(batches)), std::invalid_argument);
  ImpostorBatch none{nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr, 0};
  batches = {none};
  EXPECT_NO_THROW(renderer.render({}, identity, identity, BodyBatches(batches)));
}

}  // namespace
}  // namespace strata
