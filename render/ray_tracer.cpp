#include "render/ray_tracer.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>
#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include "profiling/profiler.h"
#include "render/appearance.h"
#include "render/ground_pass.h"

namespace strata {
namespace {

// The sun and sky of RenderQuality::High (render/crowd_renderer.cpp sunlight(): the same numbers, so a traced
// frame and a GL frame of one scene are lit alike).
struct Light {
  glm::vec3 to_sun{0.0f, 1.0f, 0.0f};
  glm::vec3 sun_color{2.3f, 2.18f, 1.98f};
  glm::vec3 sky_color{0.42f, 0.50f, 0.66f};
  glm::vec3 bounce_color{0.20f, 0.18f, 0.15f};
  float exposure = 0.8f;
};

// shading.glsl's functions, line for line.
glm::vec3 srgb_to_linear(const glm::vec3& c) {
  glm::vec3 out;
  for (int k = 0; k < 3; ++k)
    out[k] = c[k] < 0.04045f ? c[k] / 12.92f : std::pow((c[k] + 0.055f) / 1.055f, 2.4f);
  return out;
}
glm::vec3 display(const Light& light, glm::vec3 c) {
  c *= light.exposure;
  c = glm::clamp((c * (2.51f * c + 0.03f)) / (c * (2.43f * c + 0.59f) + 0.14f), 0.0f, 1.0f);
  glm::vec3 out;
  for (int k = 0; k < 3; ++k)
    out[k] = c[k] < 0.0031308f ? 12.92f * c[k] : 1.055f * std::pow(c[k], 1.0f / 2.4f) - 0.055f;
  return out;
}
glm::vec3 shade(const Light& l, const glm::vec3& world, const glm::vec3& eye, const glm::vec3& n,
                const glm::vec3& albedo, float skin, float ao, float visible) {
  const glm::vec3 to_eye = glm::normalize(eye - world);
  const float ndl = glm::dot(n, l.to_sun);
  const float lambert = std::max(ndl, 0.0f);
  constexpr float kWrap = 0.45f;
  const float wrapped = std::max((ndl + kWrap) / (1.0f + kWrap), 0.0f);
  const glm::vec3 diffuse = glm::vec3(lambert) + skin * (wrapped - lambert) * glm::vec3(0.75f, 0.30f, 0.20f);
  const glm::vec3 half_vector = glm::normalize(l.to_sun + to_eye);
  const float gloss = glm::mix(12.0f, 28.0f, skin);
  const float specular =
      glm::mix(0.015f, 0.08f, skin) * std::pow(std::max(glm::dot(n, half_vector), 0.0f), gloss) * (ndl >= 0.0f ? 1.0f : 0.0f);
  const float rim = std::pow(1.0f - std::clamp(glm::dot(n, to_eye), 0.0f, 1.0f), 4.0f) * glm::mix(0.06f, 0.12f, skin);
  const glm::vec3 ambient = glm::mix(l.bounce_color, l.sky_color, 0.5f + 0.5f * n.y);
  const glm::vec3 light = l.sun_color * diffuse * visible + ambient * ao;
  return albedo * light + l.sun_color * specular * visible + l.sky_color * rim * ao;
}
// body_shaded.vert's per-vertex variation: a hash of the vertex number, the same on every walker.
float variation(std::size_t local) {
  const float s = std::sin(static_cast<float>(local) * 12.9898f) * 43758.5453f;
  return 0.975f + 0.05f * (s - std::floor(s));
}

void check_error(RTCDevice device, const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE) throw std::runtime_error(std::string("ray tracer: ") + what + " failed (Embree error " + std::to_string(int(e)) + ")");
}

// One CPU-skinned batch of this frame (a hit's walker is found through RayTracer::Impl::owner).
struct TracedBatch {
  BodyDrawInput input;
  std::size_t triangles_per_walker = 0;
  std::vector<glm::vec4> palettes;  // kSurfaceMaterialCount per walker
};

}  // namespace

struct RayTracer::Impl {
  RTCDevice device = nullptr;
  // The scene persists while the frame's structure does (the batches' topologies, walker counts and strides, the
  // props): then a frame only copies the walkers' vertices and refits each walker's BVH (RTC_BUILD_QUALITY_REFIT,
  // ~15 ns a triangle), and the top level is rebuilt over the walkers. A new structure builds a new scene.
  RTCScene scene = nullptr;
  struct Batch {
    std::vector<std::uint32_t> triangles;  // the level's triangles, copied (the scene refers to them)
    std::size_t stride = 0, vertex_count = 0;  // the walkers are geometry.size()
    std::vector<float> vertices;           // walkers * stride interleaved, plus one float of padding for SSE loads
    std::vector<unsigned> geometry;        // per walker
    std::vector<std::uint8_t> enabled;     // per walker: off for a frame with a non-finite vertex
  };
  std::vector<Batch> batches;
  std::uint64_t scene_props_key = 0;
  unsigned props_geometry = RTC_INVALID_GEOMETRY_ID;
  // geometry id -> (batch, walker) of the body geometries; the props geometry is props_geometry.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> owner;
  std::vector<PropVertex> props;
  std::vector<float> prop_vertices;
  std::vector<std::uint32_t> prop_indices;
  std::uint64_t props_key = 0;

  void release_scene() {
    if (scene) rtcReleaseScene(scene);
    scene = nullptr;
  }
};

RayTracer::RayTracer() : impl_(std::make_unique<Impl>()) {
  impl_->device = rtcNewDevice(nullptr);
  if (!impl_->device)
    throw std::runtime_error("ray tracer: cannot create an Embree device (Embree error " +
                             std::to_string(int(rtcGetDeviceError(nullptr))) + ")");
}

RayTracer::~RayTracer() {
  if (!impl_) return;
  impl_->release_scene();
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

void RayTracer::set_props(std::uint64_t key, std::span<const PropVertex> triangles) {
  if (key == impl_->props_key && triangles.size() == impl_->props.size()) return;
  impl_->props.assign(triangles.begin(), triangles.end());
  impl_->props_key = triangles.empty() ? 0 : key;
  impl_->prop_vertices.clear();
  impl_->prop_indices.clear();
  for (std::size_t i = 0; i < impl_->props.size(); ++i) {
    const glm::vec3& p = impl_->props[i].position;
    impl_->prop_vertices.insert(impl_->prop_vertices.end(), {p.x, p.y, p.z});
    impl_->prop_indices.push_back(static_cast<std::uint32_t>(i));
  }
  impl_->prop_vertices.push_back(0.0f);  // padding
}

void RayTracer::render(const BodySource& bodies, std::span<const glm::vec3> ground_points, const glm::mat4& view,
                       const glm::mat4& projection, const RenderOptions& options, int width, int height,
                       std::vector<std::uint8_t>& rgba, Profiler* profiler) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("ray tracer: the image size must be positive");
  // Every batch checked before any work.
  std::vector<TracedBatch> batches;
  for (std::size_t k = 0; k < bodies.batch_count(); ++k) {
    const BodyBatch batch = bodies.batch(k);
    const BodyDrawInput* b = std::get_if<BodyDrawInput>(&batch);
    if (!b)
      throw std::invalid_argument("ray tracer: it traces skinned meshes only, not impostors (use --level 0, 1 or 2)");
    if (b->walker_count == 0 || b->vertex_count == 0 || b->triangles.empty()) continue;
    if (!b->px || !b->py || !b->pz || !b->nx || !b->ny || !b->nz || b->stride < b->vertex_count ||
        b->triangles.size() % 3 != 0)
      throw std::invalid_argument("ray tracer: a body batch's arrays or sizes disagree");
    for (std::uint32_t i : b->triangles)
      if (i >= b->vertex_count) throw std::invalid_argument("ray tracer: a triangle index is out of range");
    if ((!b->materials.empty() && b->materials.size() != b->vertex_count) ||
        (!b->material_cut.empty() && b->material_cut.size() != b->vertex_count) ||
        (!b->ambient_occlusion.empty() && b->ambient_occlusion.size() != b->vertex_count))
      throw std::invalid_argument("ray tracer: a body batch's per-vertex lists disagree with its vertex count");
    TracedBatch t;
    t.input = *b;
    t.triangles_per_walker = b->triangles.size() / 3;
    batches.push_back(std::move(t));
  }

  Impl& r = *impl_;
  Light light;
  {
    const float length = glm::length(options.to_sun);
    light.to_sun = length > 1e-6f && std::isfinite(length) ? options.to_sun / length : glm::vec3(0.0f, 1.0f, 0.0f);
  }
  const WalkerPalette plain = plain_palette(options.skin_color);

  // ---- The scene: one geometry per walker (refitted), the props ---------------------------------------------
  std::optional<Profiler::ScopedTimer> scope;
  if (profiler) scope.emplace(*profiler, profiler->intern("bvh"));
  // A walker's geometry: its block of the batch's vertex array (shared, so the array must never move while the
  // scene lives) and the level's triangles.
  auto add_walker = [&](std::size_t k, std::size_t w) {
    Impl::Batch& s = r.batches[k];
    RTCGeometry g = rtcNewGeometry(r.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_REFIT);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s.vertices.data(),
                               3 * sizeof(float) * w * s.stride, 3 * sizeof(float), s.vertex_count);
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, s.triangles.data(), 0,
                               3 * sizeof(std::uint32_t), s.triangles.size() / 3);
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(r.scene, g);
    rtcReleaseGeometry(g);
    s.geometry.push_back(id);
    s.enabled.push_back(1);
    if (r.owner.size() <= id) r.owner.resize(id + 1);
    r.owner[id] = {static_cast<std::uint32_t>(k), static_cast<std::uint32_t>(w)};
  };
  // The same structure but for walker counts (walkers culled or spawned, agents arriving) keeps the scene: the
  // batch gains or loses geometries at its end, as long as its vertex array need not move. Rebuilding instead
  // cost 2.5 s for 1,000 walkers, every time one walked into or out of the view.
  bool same = r.scene && r.batches.size() == batches.size() && r.scene_props_key == r.props_key;
  for (std::size_t k = 0; same && k < batches.size(); ++k) {
    const BodyDrawInput& b = batches[k].input;
    const Impl::Batch& s = r.batches[k];
    same = s.triangles.size() == b.triangles.size() && s.stride == b.stride &&
           s.vertex_count == b.vertex_count && std::equal(s.triangles.begin(), s.triangles.end(), b.triangles.begin()) &&
           3 * b.walker_count * b.stride + 1 <= s.vertices.capacity();
  }
  if (same) {
    for (std::size_t k = 0; k < batches.size(); ++k) {
      Impl::Batch& s = r.batches[k];
      const std::size_t walkers = batches[k].input.walker_count;
      s.vertices.resize(3 * walkers * s.stride + 1);  // within capacity: the shared blocks stay where they are
      while (s.geometry.size() > walkers) {
        rtcDetachGeometry(r.scene, s.geometry.back());
        s.geometry.pop_back();
        s.enabled.pop_back();
      }
      for (std::size_t w = s.geometry.size(); w < walkers; ++w) add_walker(k, w);
    }
  } else {
    r.release_scene();
    r.scene = rtcNewScene(r.device);
    rtcSetSceneFlags(r.scene, RTC_SCENE_FLAG_DYNAMIC);
    rtcSetSceneBuildQuality(r.scene, RTC_BUILD_QUALITY_LOW);
    r.batches.assign(batches.size(), {});
    r.owner.clear();
    for (std::size_t k = 0; k < batches.size(); ++k) {
      const BodyDrawInput& b = batches[k].input;
      Impl::Batch& s = r.batches[k];
      s.triangles.assign(b.triangles.begin(), b.triangles.end());
      s.stride = b.stride;
      s.vertex_count = b.vertex_count;
      // Room for a quarter more walkers, so a crowd that grows a little keeps its scene.
      s.vertices.reserve(3 * (b.walker_count + b.walker_count / 4 + 1) * b.stride + 1);
      s.vertices.assign(3 * b.walker_count * b.stride + 1, 0.0f);
      for (std::size_t w = 0; w < b.walker_count; ++w) add_walker(k, w);
    }
    r.props_geometry = RTC_INVALID_GEOMETRY_ID;
    if (!r.prop_indices.empty()) {
      RTCGeometry g = rtcNewGeometry(r.device, RTC_GEOMETRY_TYPE_TRIANGLE);
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, r.prop_vertices.data(), 0,
                                 3 * sizeof(float), r.props.size());
      rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, r.prop_indices.data(), 0,
                                 3 * sizeof(std::uint32_t), r.prop_indices.size() / 3);
      rtcCommitGeometry(g);
      r.props_geometry = rtcAttachGeometry(r.scene, g);
      rtcReleaseGeometry(g);
    }
    r.scene_props_key = r.props_key;
    check_error(r.device, "making the scene");
  }
  triangles_traced_ = 0;
  std::vector<std::uint8_t> finite;
  for (std::size_t k = 0; k < batches.size(); ++k) {
    TracedBatch& t = batches[k];
    const BodyDrawInput& b = t.input;
    Impl::Batch& s = r.batches[k];
    fill_palettes(b.walker_keys, b.walker_count, plain, t.palettes);
    finite.assign(b.walker_count, 1);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, b.walker_count, 1), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t w = range.begin(); w < range.end(); ++w)
        for (std::size_t v = 0; v < b.vertex_count; ++v) {
          const std::size_t i = w * b.stride + v;
          s.vertices[3 * i] = b.px[i];
          s.vertices[3 * i + 1] = b.py[i];
          s.vertices[3 * i + 2] = b.pz[i];
          if (!std::isfinite(b.px[i] + b.py[i] + b.pz[i])) finite[w] = 0;
        }
    });
    // Embree's calls one walker after another (cheap: the refit itself happens in rtcCommitScene). A walker with a
    // non-finite vertex is left out of the frame rather than refitted around NaN bounds.
    for (std::size_t w = 0; w < b.walker_count; ++w) {
      RTCGeometry g = rtcGetGeometry(r.scene, s.geometry[w]);
      if (finite[w] != s.enabled[w]) {
        if (finite[w]) rtcEnableGeometry(g);
        else rtcDisableGeometry(g);
        s.enabled[w] = finite[w];
      }
      if (finite[w]) {
        rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(g);
      }
    }
    for (std::uint8_t e : s.enabled) triangles_traced_ += e ? t.triangles_per_walker : 0;
  }
  rtcCommitScene(r.scene);
  check_error(r.device, "building the scene");
  RTCScene scene = r.scene;
  const unsigned props_geometry = r.props_geometry;

  // ---- Rays ------------------------------------------------------------------------------------------------
  if (profiler) scope.emplace(*profiler, profiler->intern("trace"));
  const glm::mat4 inverse_view_projection = glm::inverse(projection * view);
  const glm::vec3 eye(glm::inverse(view)[3]);
  const GroundExtent ground = ground_extent(ground_points);
  const bool draw_ground = options.draw_ground && ground.half_size > 0.0f;
  const glm::vec3 ground_albedo = srgb_to_linear(options.ground_color);
  const glm::vec3 clear(options.clear_color);
  auto direction = [&](float x, float y) {
    const glm::vec2 ndc(2.0f * x / static_cast<float>(width) - 1.0f, 1.0f - 2.0f * y / static_cast<float>(height));
    const glm::vec4 far_point = inverse_view_projection * glm::vec4(ndc, 1.0f, 1.0f);
    return glm::normalize(glm::vec3(far_point) / far_point.w - eye);
  };
  auto occluded = [&](const glm::vec3& from) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray{};
    ray.org_x = from.x, ray.org_y = from.y, ray.org_z = from.z;
    ray.dir_x = light.to_sun.x, ray.dir_y = light.to_sun.y, ray.dir_z = light.to_sun.z;
    ray.tnear = 0.0f;
    ray.tfar = std::numeric_limits<float>::infinity();
    ray.mask = 0xFFFFFFFFu;
    rtcOccluded1(scene, &context, &ray);
    return ray.tfar < 0.0f;
  };
  // The ground at a pixel: the grid of ground_shaded.frag with its screen-space line width from the neighbouring
  // pixels' hits (GL's fwidth), lit, then faded into the clear colour towards the extent's edge.
  auto ground_colour = [&](const glm::vec3& hit, float px, float py) -> std::optional<glm::vec3> {
    if (std::abs(hit.x - ground.center.x) > ground.half_size || std::abs(hit.z - ground.center.y) > ground.half_size)
      return std::nullopt;
    auto on_plane = [&](float x, float y) {
      const glm::vec3 d = direction(x, y);
      return std::abs(d.y) > 1e-7f ? eye + d * (-eye.y / d.y) : hit;
    };
    const glm::vec3 dx = on_plane(px + 1.0f, py) - hit, dy = on_plane(px, py + 1.0f) - hit;
    const glm::vec2 w = glm::max(glm::vec2(std::abs(dx.x) + std::abs(dy.x), std::abs(dx.z) + std::abs(dy.z)), glm::vec2(1e-5f));
    const glm::vec2 p(hit.x, hit.z);
    const glm::vec2 g = glm::abs(glm::fract(p - 0.5f) - 0.5f) / w;
    const float fade_line = 1.0f - glm::smoothstep(0.1f, 0.4f, std::max(w.x, w.y));
    const float line = (1.0f - std::min(std::min(g.x, g.y), 1.0f)) * fade_line;
    const glm::vec3 albedo = ground_albedo * glm::mix(1.0f, 0.8f, line);
    const float visible = occluded(hit + glm::vec3(0.0f, 1e-4f, 0.0f)) ? 0.0f : 1.0f;
    const glm::vec3 c = display(light, shade(light, hit, eye, glm::vec3(0, 1, 0), albedo, 0.0f, 1.0f, visible));
    const float fade = glm::smoothstep(ground.fade_start, ground.half_size, glm::length(p - ground.center));
    return glm::mix(c, clear, fade);
  };
  auto body_colour = [&](const TracedBatch& t, std::size_t walker, std::size_t tri, float u, float v,
                         const glm::vec3& hit, const glm::vec3& ray_dir) {
    const BodyDrawInput& b = t.input;
    const float bary[3] = {1.0f - u - v, u, v};
    glm::vec3 n(0.0f), above(0.0f), below(0.0f);
    float cut = 0.0f, ao = 0.0f, skin_above = 0.0f, skin_below = 0.0f;
    for (int c = 0; c < 3; ++c) {
      const std::size_t local = b.triangles[3 * tri + static_cast<std::size_t>(c)];
      const std::size_t i = walker * b.stride + local;
      n += bary[c] * glm::vec3(b.nx[i], b.ny[i], b.nz[i]);
      const std::uint8_t classes = b.materials.empty() ? 0 : b.materials[local];
      const glm::vec4& pa = t.palettes[walker * kSurfaceMaterialCount + std::min<std::size_t>(classes & 15u, kSurfaceMaterialCount - 1)];
      const glm::vec4& pb = t.palettes[walker * kSurfaceMaterialCount + std::min<std::size_t>(classes >> 4, kSurfaceMaterialCount - 1)];
      const float h = variation(local);
      above += bary[c] * glm::vec3(pa) * h;
      below += bary[c] * glm::vec3(pb) * h;
      skin_above += bary[c] * pa.a;
      skin_below += bary[c] * pb.a;
      cut += bary[c] * (b.material_cut.empty() ? 1.0f : b.material_cut[local]);
      ao += bary[c] * (b.ambient_occlusion.empty() ? 1.0f : b.ambient_occlusion[local]);
    }
    const float length = glm::length(n);
    n = length > 1e-12f && std::isfinite(length) ? n / length : -ray_dir;
    const bool is_above = cut >= 0.0f;
    // Off the surface along its normal (towards the side the ray came from) before looking for the sun.
    const glm::vec3 lift = (glm::dot(n, ray_dir) < 0.0f ? n : -n) * 1e-3f;
    const float visible = occluded(hit + lift) ? 0.0f : 1.0f;
    return display(light, shade(light, hit, eye, n, is_above ? above : below, is_above ? skin_above : skin_below, ao, visible));
  };
  auto prop_colour = [&](unsigned prim, float u, float v, const glm::vec3& hit, const glm::vec3& ray_dir) {
    const PropVertex* tri = &r.props[3 * static_cast<std::size_t>(prim)];
    const float bary[3] = {1.0f - u - v, u, v};
    glm::vec3 n(0.0f), albedo(0.0f);
    for (int c = 0; c < 3; ++c) n += bary[c] * tri[c].normal, albedo += bary[c] * glm::vec3(tri[c].color);
    const float length = glm::length(n);
    n = length > 1e-12f ? n / length : -ray_dir;
    const glm::vec3 lift = (glm::dot(n, ray_dir) < 0.0f ? n : -n) * 1e-3f;
    const float visible = occluded(hit + lift) ? 0.0f : 1.0f;
    return display(light, shade(light, hit, eye, n, srgb_to_linear(albedo), 0.0f, 1.0f, visible));
  };

  rgba.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4);
  tbb::parallel_for(tbb::blocked_range2d<int>(0, height, 8, 0, width, 8), [&](const tbb::blocked_range2d<int>& tile) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (int y = tile.rows().begin(); y < tile.rows().end(); ++y)
      for (int x = tile.cols().begin(); x < tile.cols().end(); ++x) {
        const float px = static_cast<float>(x) + 0.5f, py = static_cast<float>(y) + 0.5f;
        const glm::vec3 d = direction(px, py);
        RTCRayHit rh{};
        rh.ray.org_x = eye.x, rh.ray.org_y = eye.y, rh.ray.org_z = eye.z;
        rh.ray.dir_x = d.x, rh.ray.dir_y = d.y, rh.ray.dir_z = d.z;
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = std::numeric_limits<float>::infinity();
        rh.ray.mask = 0xFFFFFFFFu;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &context, &rh);
        const float ground_t = draw_ground && d.y < -1e-7f && eye.y > 0.0f ? -eye.y / d.y : std::numeric_limits<float>::infinity();
        glm::vec3 colour = clear;
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID && rh.ray.tfar <= ground_t) {
          const glm::vec3 hit = eye + d * rh.ray.tfar;
          if (rh.hit.geomID == props_geometry) {
            colour = prop_colour(rh.hit.primID, rh.hit.u, rh.hit.v, hit, d);
          } else {
            const auto [batch, walker] = r.owner[rh.hit.geomID];
            colour = body_colour(batches[batch], walker, rh.hit.primID, rh.hit.u, rh.hit.v, hit, d);
          }
        } else if (std::isfinite(ground_t)) {
          if (const std::optional<glm::vec3> g = ground_colour(eye + d * ground_t, px, py)) colour = *g;
        }
        std::uint8_t* out = rgba.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 4;
        for (int c = 0; c < 3; ++c)
          out[c] = static_cast<std::uint8_t>(std::lround(std::clamp(colour[c], 0.0f, 1.0f) * 255.0f));
        out[3] = 255;
      }
  });
  check_error(r.device, "tracing");
}

}  // namespace strata
