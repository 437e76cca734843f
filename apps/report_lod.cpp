// strata report lod: what the level-of-detail tiers cost and what they look like.
//
//   image quality  a crowd shot (eye height across the track, and from above) rendered tiered (--level auto:
//                  meshes within the budget, impostors beyond) and with every walker a level-0 mesh, same camera,
//                  same walkers: PSNR and mean absolute error over the frame
//   pop            walkers crossing the impostor threshold: the change between consecutive frames inside each
//                  crossing walker's screen rectangle, against the same walkers when they stay meshes
//   memory         bytes per walker in each tier (the table rows, the skinned vertices, the level-of-detail
//                  scratch), and the resident memory of the largest crowd run
//   speed          simulate + render, the crowd filling a 1280x720 view, for 1,000 / 10,000 / 100,000 walkers
//   bake           seconds to bake the impostor atlas (uncached)
//
// Everything is measured in this run on this machine; nothing is a stored figure.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

#include "apps/cli_support.h"
#include "apps/commands.h"
#include "apps/json_output.h"
#include "apps/scene_options.h"
#include "io/image_writer.h"
#include "render/gl_context.h"
#include "render/impostor_bake.h"
#include "render/scene_draw.h"
#include "scene/body_settings.h"
#include "scene/crowd.h"
#include "scene/scene_setup.h"
#include "scene/step.h"

namespace strata::cli {
namespace {

struct LodReportOptions {
  SceneOptions scene;
  std::string json;
  std::string images;
  int width = 1280, height = 720;
  std::vector<std::size_t> counts = {1000, 10000, 100000};
  std::size_t frames = 30;            // timed frames per crowd size (fewer for the largest)
  std::size_t quality_walkers = 1000;
  std::size_t pop_walkers = 120;
  std::size_t pop_frames = 45;
  // Low by default: docs/lod.md's figures (frame rates, image error) are measured with the render benchmarks'
  // shading; --quality high draws what `strata crowd` draws (the README's pictures).
  RenderQuality quality = RenderQuality::Low;
};

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// The process's high-water resident set (VmHWM), KiB: what the largest crowd needed at its peak.
long peak_resident_kib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

using Image = std::vector<std::uint8_t>;  // RGBA8, rows top to bottom

struct ImageError {
  double psnr_db = 0.0, mean_abs_error = 0.0;
};

// Over the RGB channels of the pixels in [x0, x1) x [y0, y1).
ImageError compare(const Image& a, const Image& b, int width, int x0, int y0, int x1, int y1) {
  double squared = 0.0, absolute = 0.0;
  std::size_t n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      for (int c = 0; c < 3; ++c) {
        const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)) * 4 + static_cast<std::size_t>(c);
        const double d = double(a[i]) - double(b[i]);
        squared += d * d;
        absolute += std::abs(d);
        ++n;
      }
  ImageError e;
  if (n == 0) return e;
  const double mse = squared / double(n);
  e.psnr_db = mse > 0.0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : 99.0;
  e.mean_abs_error = absolute / double(n);
  return e;
}

std::unique_ptr<Crowd> make_crowd(const LodReportOptions& o, std::size_t walkers, DetailLevel level) {
  SceneOptions s = o.scene;
  s.walkers = walkers;
  s.level = level;
  s.motion = "walk";
  return build_scene(s);
}

// The radius of the stadium track's outer lane for `walkers` (scene/spawn.cpp: sqrt(n) lanes, CrowdConfig's
// defaults), to put an eye-height camera at the crowd's edge.
float outer_radius(std::size_t walkers) {
  const float lanes = std::max(1.0f, std::round(std::sqrt(static_cast<float>(walkers))));
  return 2.5f + 0.9f * lanes + 2.5f;
}

// Bytes of one row of `table`: every field's components, 4 bytes each.
std::size_t row_bytes(const SoaTable& table) {
  std::size_t bytes = 0;
  for (const FieldDesc& f : table.fields()) bytes += f.width * 4;
  return bytes;
}

struct Renderer {
  std::unique_ptr<GlContext> context;
  std::unique_ptr<CrowdRenderer> renderer;
  int width = 0, height = 0;
  float aspect() const { return static_cast<float>(width) / static_cast<float>(height); }
};

void render(Crowd& crowd, Renderer& r, const OrbitCamera& camera, RenderScratch& scratch, Image* pixels) {
  render_frame(crowd, *r.renderer, camera, r.aspect(), r.height, scratch);
  if (pixels) r.renderer->read_rgba(*pixels);
}

void save(const LodReportOptions& o, const std::string& name, const Image& pixels, int width, int height) {
  if (o.images.empty()) return;
  write_image(std::filesystem::path(o.images) / name, width, height, 4, pixels);
}

// The tiered frame against every walker a level-0 mesh, from `camera` (framed on the crowd when `frame`).
nlohmann::json quality_shot(const LodReportOptions& o, Renderer& r, const std::shared_ptr<const ImpostorAtlas>& atlas, OrbitCamera camera,
                            bool frame, const std::string& name) {
  auto tiered = make_crowd(o, o.quality_walkers, DetailLevel::automatic());
  auto reference = make_crowd(o, o.quality_walkers, DetailLevel::mesh(0));
  tiered->impostor_atlas = atlas;
  RenderScratch scratch;
  if (frame) frame_crowd(*tiered, camera, r.aspect(), scratch);
  Profiler profiler(1, false);
  for (Crowd* c : {tiered.get(), reference.get()}) {
    set_crowd_camera(*c, camera, r.aspect(), r.height);
    for (int f = 0; f < 10; ++f) step(*c, 1.0f / 30.0f, profiler);
  }
  Image a, b;
  render(*tiered, r, camera, scratch, &a);
  const std::size_t impostors = r.renderer->impostors_drawn();
  render(*reference, r, camera, scratch, &b);
  const ImageError e = compare(a, b, r.width, 0, 0, r.width, r.height);
  save(o, "lod_" + name + "_tiered.png", a, r.width, r.height);
  save(o, "lod_" + name + "_level0.png", b, r.width, r.height);
  std::size_t meshes = 0;
  for (int k = 0; k < kMaxMeshLevels; ++k) meshes += tiered->table(mesh_slot(k)).size();
  std::printf("  %-6s tiered vs level 0: PSNR %.2f dB, mean abs error %.3f (%zu meshes, %zu impostors)\n", name.c_str(),
              e.psnr_db, e.mean_abs_error, meshes, impostors);
  return {{"image_psnr_db", e.psnr_db}, {"image_mean_abs_error", e.mean_abs_error}, {"meshes", meshes},
          {"impostors", impostors}, {"walkers", o.quality_walkers}};
}

// A walker's screen rectangle (pixels, clamped), from its bounding sphere.
struct Rect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
};
Rect screen_rect(const glm::mat4& view_projection, const glm::vec3& center, float radius, int width, int height) {
  float lo_x = 1e9f, lo_y = 1e9f, hi_x = -1e9f, hi_y = -1e9f;
  for (int i = 0; i < 8; ++i) {
    const glm::vec3 p = center + radius * glm::vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
    const glm::vec4 clip = view_projection * glm::vec4(p, 1.0f);
    if (clip.w <= 1e-4f) return {};
    const float x = (clip.x / clip.w * 0.5f + 0.5f) * static_cast<float>(width);
    const float y = (0.5f - clip.y / clip.w * 0.5f) * static_cast<float>(height);
    lo_x = std::min(lo_x, x), hi_x = std::max(hi_x, x), lo_y = std::min(lo_y, y), hi_y = std::max(hi_y, y);
  }
  Rect r{static_cast<int>(std::floor(lo_x)), static_cast<int>(std::floor(lo_y)), static_cast<int>(std::ceil(hi_x)),
         static_cast<int>(std::ceil(hi_y))};
  r.x0 = std::clamp(r.x0, 0, width), r.x1 = std::clamp(r.x1, 0, width);
  r.y0 = std::clamp(r.y0, 0, height), r.y1 = std::clamp(r.y1, 0, height);
  return r;
}

// Walkers walking across the impostor threshold under a fixed camera: each crossing's consecutive-frame change in
// the tiered run against the same two frames of a run where every walker stays a mesh.
nlohmann::json pop_test(const LodReportOptions& o, Renderer& r, const std::shared_ptr<const ImpostorAtlas>& atlas) {
  auto tiered = make_crowd(o, o.pop_walkers, DetailLevel::automatic());
  auto meshes = make_crowd(o, o.pop_walkers, DetailLevel::automatic());
  tiered->impostor_atlas = atlas;
  meshes->lod.policy.impostor_px = 0.0f;  // never an impostor
  meshes->lod.policy.mesh_budget = 0;
  // A camera at eye height whose impostor distance falls in the middle of the track.
  OrbitCamera camera;
  const float focal = static_cast<float>(r.height) / (2.0f * std::tan(0.5f * camera.fov_y));
  const float threshold_m = focal * tiered->skin.body_height / tiered->lod.policy.impostor_px;
  camera.target = glm::vec3(0.0f, 1.0f, 0.0f);
  camera.yaw = 1.2f;
  camera.distance = threshold_m;
  camera.pitch = 0.05f;
  const glm::mat4 vp = camera.projection(r.aspect()) * camera.view();
  Profiler profiler(1, false);
  RenderScratch scratch;
  for (Crowd* c : {tiered.get(), meshes.get()}) set_crowd_camera(*c, camera, r.aspect(), r.height);
  Image a_prev, a, b_prev, b;
  std::vector<DetailSlot> previous;
  double pop_max = 0.0, pop_sum = 0.0, mesh_max = 0.0, mesh_sum = 0.0, all_max = 0.0, all_sum = 0.0;
  double excess_max = 0.0;
  std::size_t crossings = 0, all_count = 0;
  for (std::size_t f = 0; f < o.pop_frames; ++f) {
    step(*tiered, 1.0f / 30.0f, profiler);
    step(*meshes, 1.0f / 30.0f, profiler);
    render(*tiered, r, camera, scratch, &a);
    render(*meshes, r, camera, scratch, &b);
    const std::vector<Entity> walkers = tiered->world.entities();
    std::vector<DetailSlot> now(walkers.size());
    for (std::size_t w = 0; w < walkers.size(); ++w) now[w] = tiered->slot_of(walkers[w]);
    if (!previous.empty()) {
      // Every walker of the all-mesh run, crossing or not: how much a mesh walker's rectangle changes between two
      // frames anyway (its own motion), the scale a pop is judged against.
      const std::vector<Entity> stay = meshes->world.entities();
      for (const Entity e : stay) {
        const EntityLocation at = meshes->world.location(e);
        const SoaTable& t = meshes->world.table(at.table);
        if (slot_index(meshes->slot_of(e)) >= kMaxMeshLevels) continue;
        const float height = meshes->skin.body_height * t.f32(kWalkerPlacement, 4)[at.block];
        const glm::vec3 center(t.f32(kWalkerPlacement, 0)[at.block], 0.5f * height, t.f32(kWalkerPlacement, 2)[at.block]);
        const Rect rect = screen_rect(vp, center, 0.6f * height, r.width, r.height);
        if (rect.empty() || rect.x1 - rect.x0 < 4) continue;
        const double still = compare(b, b_prev, r.width, rect.x0, rect.y0, rect.x1, rect.y1).mean_abs_error;
        all_max = std::max(all_max, still), all_sum += still, ++all_count;
      }
      for (std::size_t w = 0; w < walkers.size(); ++w) {
        const bool was_impostor = previous[w] == DetailSlot::Impostor, is_impostor = now[w] == DetailSlot::Impostor;
        const bool was_mesh = slot_index(previous[w]) < kMaxMeshLevels, is_mesh = slot_index(now[w]) < kMaxMeshLevels;
        if (!((was_mesh && is_impostor) || (was_impostor && is_mesh))) continue;
        const EntityLocation at = tiered->world.location(walkers[w]);
        const SoaTable& t = tiered->world.table(at.table);
        const float scale = t.f32(kWalkerPlacement, 4)[at.block];
        const float height = tiered->skin.body_height * scale;
        const glm::vec3 center(t.f32(kWalkerPlacement, 0)[at.block], 0.5f * height, t.f32(kWalkerPlacement, 2)[at.block]);
        const Rect rect = screen_rect(vp, center, 0.6f * height, r.width, r.height);
        if (rect.empty()) continue;
        const double pop = compare(a, a_prev, r.width, rect.x0, rect.y0, rect.x1, rect.y1).mean_abs_error;
        const double still = compare(b, b_prev, r.width, rect.x0, rect.y0, rect.x1, rect.y1).mean_abs_error;
        pop_max = std::max(pop_max, pop), pop_sum += pop;
        excess_max = std::max(excess_max, pop - still);
        mesh_max = std::max(mesh_max, still), mesh_sum += still;
        ++crossings;
      }
    }
    previous = now;
    a_prev.swap(a);
    b_prev.swap(b);
  }
  std::printf("  pop: %zu crossings, consecutive-frame mean abs error in the walker's rectangle: max %.3f mean %.3f; "
              "the same walkers staying meshes: max %.3f mean %.3f (excess at most %.3f); any mesh walker: max %.3f "
              "mean %.3f\n",
              crossings, pop_max, crossings ? pop_sum / double(crossings) : 0.0, mesh_max,
              crossings ? mesh_sum / double(crossings) : 0.0, excess_max, all_max,
              all_count ? all_sum / double(all_count) : 0.0);
  return {{"pop_mean_abs_error_max", pop_max},
          {"pop_mean_abs_error_mean", crossings ? pop_sum / double(crossings) : 0.0},
          {"mesh_consecutive_mean_abs_error_max", mesh_max},
          {"mesh_consecutive_mean_abs_error_mean", crossings ? mesh_sum / double(crossings) : 0.0},
          {"pop_excess_mean_abs_error_max", excess_max},
          {"mesh_walker_consecutive_mean_abs_error_max", all_max},
          {"mesh_walker_consecutive_mean_abs_error_mean", all_count ? all_sum / double(all_count) : 0.0},
          {"crossings", crossings},
          {"walkers", o.pop_walkers},
          {"frames", o.pop_frames},
          {"threshold_m", threshold_m}};
}

// The switch up close: one walker at the impostor threshold's distance, as its level-2 mesh (left) and as the
// impostor that replaces it (right), cropped around it and enlarged 4x (nearest), for the README.
void switch_figure(const LodReportOptions& o, Renderer& r, const std::shared_ptr<const ImpostorAtlas>& atlas) {
  if (o.images.empty()) return;
  auto one = [&](DetailLevel level) {
    LodReportOptions single = o;
    auto c = make_crowd(single, 1, level);
    c->impostor_atlas = atlas;
    return c;
  };
  auto mesh = one(DetailLevel::mesh(2));
  auto impostor = one(DetailLevel::impostor());
  OrbitCamera camera;
  const float focal = static_cast<float>(r.height) / (2.0f * std::tan(0.5f * camera.fov_y));
  camera.distance = focal * mesh->skin.body_height / mesh->lod.policy.impostor_px;
  camera.pitch = 0.08f;
  camera.yaw = 0.9f;
  Profiler profiler(1, false);
  RenderScratch scratch;
  Image a, b;
  for (int f = 0; f < 12; ++f)
    for (Crowd* c : {mesh.get(), impostor.get()}) step(*c, 1.0f / 30.0f, profiler);
  const SoaTable& t = mesh->table(DetailSlot::Mesh2);
  camera.target = glm::vec3(t.f32(kWalkerPlacement, 0)[0], 0.9f, t.f32(kWalkerPlacement, 2)[0]);
  render(*mesh, r, camera, scratch, &a);
  render(*impostor, r, camera, scratch, &b);
  const int h = static_cast<int>(o.scene.walkers > 0 ? 1.3f * mesh->lod.policy.impostor_px : 130.0f);
  const int w = h * 3 / 4, scale = 4;
  const int x0 = std::max(0, r.width / 2 - w / 2), y0 = std::max(0, r.height / 2 - h / 2);
  const int cw = std::min(w, r.width - x0), ch = std::min(h, r.height - y0);
  Image out(static_cast<std::size_t>(2 * cw * scale) * static_cast<std::size_t>(ch * scale) * 4);
  for (int y = 0; y < ch * scale; ++y)
    for (int x = 0; x < 2 * cw * scale; ++x) {
      const Image& src = x < cw * scale ? a : b;
      const int sx = x0 + (x % (cw * scale)) / scale, sy = y0 + y / scale;
      const std::size_t from = (static_cast<std::size_t>(sy) * static_cast<std::size_t>(r.width) + static_cast<std::size_t>(sx)) * 4;
      const std::size_t to = (static_cast<std::size_t>(y) * static_cast<std::size_t>(2 * cw * scale) + static_cast<std::size_t>(x)) * 4;
      std::copy_n(src.begin() + static_cast<std::ptrdiff_t>(from), 4, out.begin() + static_cast<std::ptrdiff_t>(to));
    }
  save(o, "lod_switch.png", out, 2 * cw * scale, ch * scale);
}

// Simulate + render `walkers` filling the view, timed.
nlohmann::json speed_run(const LodReportOptions& o, Renderer& r, const std::shared_ptr<const ImpostorAtlas>& atlas,
                         std::size_t walkers, std::size_t frames, bool save_frame) {
  const long before_kib = resident_kib();
  auto crowd = make_crowd(o, walkers, DetailLevel::automatic());
  crowd->impostor_atlas = atlas;
  // A crowd shot: from just outside the track, a little above the walkers' heads, looking across it, so walkers
  // fill the view from the nearest (meshes, within the budget) to the far side (impostors). Set before the first
  // step (the walkers start as impostors), so no step ever skins the whole crowd.
  OrbitCamera camera;
  camera.target = glm::vec3(0.0f, 1.0f, 0.0f);
  camera.yaw = 0.6f;
  camera.pitch = 0.12f;
  camera.distance = outer_radius(walkers) + 3.0f;
  camera.far_plane = std::max(camera.far_plane, 3.0f * camera.distance);
  RenderScratch scratch;
  set_crowd_camera(*crowd, camera, r.aspect(), r.height);
  Profiler profiler(1, false);
  for (int f = 0; f < 3; ++f) {  // warm-up: tiers settle, buffers grow
    step(*crowd, 1.0f / 30.0f, profiler);
    render(*crowd, r, camera, scratch, nullptr);
  }
  r.renderer->finish();
  const auto start = Clock::now();
  double sim_s = 0.0;
  for (std::size_t f = 0; f < frames; ++f) {
    const auto s0 = Clock::now();
    step(*crowd, 1.0f / 30.0f, profiler);
    sim_s += seconds_since(s0);
    render(*crowd, r, camera, scratch, nullptr);
    r.renderer->finish();
  }
  const double total = seconds_since(start);
  const long after_kib = resident_kib();
  if (save_frame) {
    Image pixels;
    r.renderer->read_rgba(pixels);
    save(o, "lod_crowd_" + std::to_string(walkers) + ".png", pixels, r.width, r.height);
  }
  nlohmann::json tiers;
  for (std::size_t s = 0; s < kDetailSlots; ++s)
    tiers[slot_name(static_cast<DetailSlot>(s))] = crowd->table(static_cast<DetailSlot>(s)).size();
  const double fps = double(frames) / total;
  std::printf("  %7zu walkers: %.1f fps (simulate %.1f ms, render %.1f ms a frame); level0 %zu level1 %zu level2 %zu "
              "impostor %zu culled %zu; resident +%.0f MiB\n",
              walkers, fps, 1000.0 * sim_s / double(frames), 1000.0 * (total - sim_s) / double(frames),
              crowd->table(DetailSlot::Mesh0).size(), crowd->table(DetailSlot::Mesh1).size(),
              crowd->table(DetailSlot::Mesh2).size(), crowd->table(DetailSlot::Impostor).size(),
              crowd->table(DetailSlot::Culled).size(), double(after_kib - before_kib) / 1024.0);
  return {{"walkers", walkers},
          {"fps", fps},
          {"frames", frames},
          {"simulate_ms", 1000.0 * sim_s / double(frames)},
          {"render_ms", 1000.0 * (total - sim_s) / double(frames)},
          {"walkers_per_tier", tiers},
          {"mesh_budget", crowd->lod.policy.mesh_budget},
          {"resident_kib_added", after_kib - before_kib}};
}

nlohmann::json bytes_per_walker(const LodReportOptions& o) {
  auto crowd = make_crowd(o, 1, DetailLevel::automatic());
  const std::size_t wide = row_bytes(crowd->table(DetailSlot::Mesh0));
  const std::size_t light = row_bytes(crowd->table(DetailSlot::Impostor));
  // The level-of-detail stage's per-row scratch (decision byte, distance), the world's entity slot (generation,
  // alive flag, table and block: 16 bytes) and, for impostors, the six floats streamed to the GL each frame.
  constexpr std::size_t kScratch = 1 + 4 + 16;
  constexpr std::size_t kInstance = 6 * 4;
  nlohmann::json j;
  j["impostor"] = light + kScratch + kInstance;
  j["culled"] = wide + kScratch;
  for (int k = 0; k < kMaxMeshLevels; ++k) {
    const std::size_t vertices = crowd->skin.layouts[static_cast<std::size_t>(k)].vertex_count;
    j["level" + std::to_string(k)] = wide + kScratch + vertices * 6 * 4;
  }
  j["wide_row"] = wide;
  j["impostor_row"] = light;
  return j;
}

int run_lod_report(const LodReportOptions& o) {
  if (!check_outputs("report lod", {{"--json", o.json}})) return kExitFailure;
  if (!o.images.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.images, ec);
    if (ec) {
      print_error("report lod", "--images " + o.images + ": " + ec.message());
      return kExitFailure;
    }
  }
  const int threads = thread_count(o.scene);
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  try {
    check_scene_inputs(o.scene);
    Renderer r;
    r.context = create_headless_gl_context();
    std::string why;
    r.renderer = make_checked_renderer(*r.context, o.width, o.height, why);
    if (!r.renderer) {
      print_error("report lod", why);
      return kExitFailure;
    }
    r.renderer->options().quality = o.quality;
    r.width = o.width, r.height = o.height;
    nlohmann::json out;
    out["shading"] = quality_name(o.quality);  // --quality ("quality" holds the image-quality shots)
    out["width"] = o.width;
    out["height"] = o.height;
    out["threads"] = threads;
    out["gl_renderer"] = r.context->renderer();

    // The atlas, baked here without the cache so the bake is timed.
    auto probe = make_crowd(o, 8, DetailLevel::automatic());
    if (!crowd_may_use_impostors(*probe)) throw std::invalid_argument("this rig cannot have impostors (it needs a body and a walk)");
    ImpostorBakeOptions bake;
    bake.muscles = probe->muscles_enabled();
    const auto shared_atlas =
        std::make_shared<const ImpostorAtlas>(bake_impostor_atlas(probe->rig(), probe->motion.style, bake));
    const ImpostorAtlas& atlas = *shared_atlas;
    std::printf("strata report lod: %dx%d, %d threads, %s\n  atlas: %d phases x %d azimuths x %d elevations, "
                "%.1f MB, baked in %.2f s\n",
                o.width, o.height, threads, r.context->renderer().c_str(), atlas.layout.phases,
                atlas.layout.azimuths, atlas.layout.elevations, double(atlas.bytes()) / 1e6, atlas.bake_seconds);
    if (!o.images.empty()) {
      // Phase 0's layer of both images, as stored (premultiplied), flipped to image order.
      const ImpostorAtlasLayout& l = atlas.layout;
      for (const auto& [name, pixels] : {std::pair{"lod_atlas_color.png", &atlas.color},
                                         std::pair{"lod_atlas_normal_depth.png", &atlas.normal_depth}}) {
        Image flipped(l.layer_bytes());
        const std::size_t row = static_cast<std::size_t>(l.layer_width()) * 4;
        for (int y = 0; y < l.layer_height(); ++y)
          std::copy_n(pixels->data() + static_cast<std::size_t>(l.layer_height() - 1 - y) * row, row,
                      flipped.data() + static_cast<std::size_t>(y) * row);
        // Opaque for viewing: the premultiplied colour over black.
        for (std::size_t i = 3; i < flipped.size(); i += 4) flipped[i] = 255;
        save(o, name, flipped, l.layer_width(), l.layer_height());
      }
    }
    out["bake_seconds"] = atlas.bake_seconds;
    out["atlas"] = {{"phases", atlas.layout.phases}, {"azimuths", atlas.layout.azimuths},
                    {"elevations", atlas.layout.elevations}, {"cell_width", atlas.layout.cell_width},
                    {"cell_height", atlas.layout.cell_height}, {"bytes", atlas.bytes()}};
    out["bytes_per_walker"] = bytes_per_walker(o);

    // Image quality: eye height at the crowd's edge, and from above.
    OrbitCamera eye;
    eye.target = glm::vec3(0.0f, 1.0f, 0.0f);
    eye.distance = outer_radius(o.quality_walkers) + 2.0f;
    eye.pitch = 0.03f;
    eye.yaw = 0.6f;
    OrbitCamera above;
    above.yaw = 0.6f;
    above.pitch = 0.9f;
    out["quality"]["eye_height"] = quality_shot(o, r, shared_atlas, eye, false, "eye");
    if (interrupted()) return interrupted_exit_code();
    out["quality"]["above"] = quality_shot(o, r, shared_atlas, above, true, "above");
    const double psnr = std::min(out["quality"]["eye_height"]["image_psnr_db"].get<double>(),
                                 out["quality"]["above"]["image_psnr_db"].get<double>());
    out["image_psnr_db"] = psnr;
    out["image_mean_abs_error"] = std::max(out["quality"]["eye_height"]["image_mean_abs_error"].get<double>(),
                                           out["quality"]["above"]["image_mean_abs_error"].get<double>());
    if (interrupted()) return interrupted_exit_code();

    switch_figure(o, r, shared_atlas);
    const nlohmann::json pop = pop_test(o, r, shared_atlas);
    out["pop"] = pop;
    out["pop_mean_abs_error_max"] = pop["pop_mean_abs_error_max"];
    if (interrupted()) return interrupted_exit_code();

    for (std::size_t i = 0; i < o.counts.size(); ++i) {
      const std::size_t n = o.counts[i];
      // Fewer frames for the largest crowds: a few seconds each is enough for a steady mean.
      const std::size_t frames = n >= 100000 ? std::max<std::size_t>(o.frames / 3, 3) : o.frames;
      const nlohmann::json run = speed_run(o, r, shared_atlas, n, frames, true);
      out["speed"].push_back(run);
      if (n == 1000 || n == 10000 || n == 100000) {
        out["fps_" + std::to_string(n)] = run["fps"];
        out["walkers_per_tier_" + std::to_string(n)] = run["walkers_per_tier"];
      }
      if (interrupted()) return interrupted_exit_code();
    }
    out["peak_resident_kib"] = peak_resident_kib();
    out["targets"] = {{"image_psnr_db_min", 30.0}, {"impostor_bytes_max", 2048}, {"fps_1000_min", 30.0},
                      {"fps_10000_min", 15.0}, {"fps_100000_min", 2.0}};
    if (!o.json.empty()) write_json_file(o.json, out);
  } catch (const std::exception& e) {
    print_error("report lod", error_text(e));
    return kExitFailure;
  }
  return 0;
}

}  // namespace

void add_lod_report(CLI::App& report, int& exit_code) {
  auto o = std::make_shared<LodReportOptions>();
  auto* cmd = report.add_subcommand(
      "lod", "Measure the level-of-detail tiers: tiered frame against all level 0 (PSNR), popping at the impostor "
             "threshold, bytes per walker per tier, frame rate for 1,000 to 100,000 walkers, atlas bake time");
  add_scene_options(*cmd, o->scene);
  cmd->add_option("--json", o->json, "Write the report here");
  cmd->add_option("--images", o->images, "Write the compared frames and one frame per crowd size into this folder");
  add_quality_option(*cmd, o->quality);
  cmd->add_option("--width", o->width, "Frame width")->capture_default_str()->check(whole_in(16, 16384));
  cmd->add_option("--height", o->height, "Frame height")->capture_default_str()->check(whole_in(16, 16384));
  cmd->add_option("--counts", o->counts, "Crowd sizes timed")->capture_default_str()
      ->check(whole_in(1, 10'000'000, true));
  cmd->add_option("--frames", o->frames, "Timed frames per crowd size (a third for 100,000 and more)")
      ->capture_default_str()->check(whole_in(1, 100000, true));
  cmd->add_option("--quality-walkers", o->quality_walkers, "Walkers in the image-quality shots")
      ->capture_default_str()->check(whole_in(1, 100000, true));
  cmd->add_option("--pop-walkers", o->pop_walkers, "Walkers in the popping test")->capture_default_str()
      ->check(whole_in(1, 100000, true));
  cmd->add_option("--pop-frames", o->pop_frames, "Frames of the popping test")->capture_default_str()
      ->check(whole_in(2, 100000, true));
  cmd->callback([o, &exit_code] { exit_code = run_lod_report(*o); });
}

}  // namespace strata::cli
