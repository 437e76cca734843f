#include "render/impostor_bake.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "components/fnv_hasher.h"
#include "io/impostor_file.h"
#include "motion/gait.h"
#include "motion/track.h"
#include "profiling/profiler.h"
#include "render/body_source.h"
#include "render/gl_program.h"
#include "render/scene_draw.h"
#include "rig/body_cache.h"
#include "rig/surface_material.h"
#include "scene/body_settings.h"
#include "scene/crowd.h"
#include "scene/spawn.h"
#include "scene/step.h"

namespace strata {
namespace {

// Bumped whenever the bake's output for the same inputs changes (framing, encoding, shaders).
constexpr std::uint32_t kBakeVersion = 3;  // 3: dress weights instead of the skin colour


// A framebuffer with an albedo and a normal-depth colour attachment (and depth), of one atlas layer's size.
struct BakeTarget {
  GlObject fbo{GlKind::kFramebuffer}, albedo{GlKind::kRenderbuffer}, normal{GlKind::kRenderbuffer},
      depth{GlKind::kRenderbuffer};
  BakeTarget(int width, int height, int samples) {
    glNamedRenderbufferStorageMultisample(albedo.id(), samples, GL_RGBA8, width, height);
    glNamedRenderbufferStorageMultisample(normal.id(), samples, GL_RGBA8, width, height);
    glNamedRenderbufferStorageMultisample(depth.id(), samples, GL_DEPTH_COMPONENT24, width, height);
    glNamedFramebufferRenderbuffer(fbo.id(), GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, albedo.id());
    glNamedFramebufferRenderbuffer(fbo.id(), GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, normal.id());
    glNamedFramebufferRenderbuffer(fbo.id(), GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth.id());
    const GLenum both[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(fbo.id(), 2, both);
    const GLenum status = glCheckNamedFramebufferStatus(fbo.id(), GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      char buf[128];
      std::snprintf(buf, sizeof buf, "impostor bake: %dx%d framebuffer incomplete (status 0x%04X)", width, height,
                    static_cast<unsigned>(status));
      throw std::runtime_error(buf);
    }
  }
};

// Steps `crowd` (one walker) forward until its gait phase is `target`, in steps of at most 1/60 s.
void walk_to_phase(Crowd& crowd, float target, Profiler& profiler) {
  const SoaTable& t = crowd.table(initial_slot(crowd));
  const float phase = t.f32(kWalkerGait, kGaitPhase)[0];
  const float cadence = t.f32(kWalkerGait, kGaitCadence)[0];
  const float cycle_seconds = 120.0f / cadence;  // two steps a cycle
  float remaining = (target - phase) - std::floor(target - phase);
  if (remaining > 0.999f) remaining = 0.0f;  // already there (float residue below the target)
  const float seconds = remaining * cycle_seconds;
  const int steps = std::max(1, static_cast<int>(std::ceil(seconds * 60.0f)));
  for (int i = 0; i < steps; ++i) step(crowd, seconds / static_cast<float>(steps), profiler);
}

}  // namespace

std::uint64_t impostor_atlas_key(const Rig& rig, const GaitStyle& style, const ImpostorBakeOptions& options) {
  FnvHasher h;
  h.value(kBakeVersion);
  h.vector(rig.skeleton.parents);
  h.vector(rig.skeleton.centers);
  if (rig.body && options.mesh_level >= 0 && options.mesh_level < static_cast<int>(rig.body->levels.size())) {
    const BodyLevel& level = rig.body->levels[static_cast<std::size_t>(options.mesh_level)];
    h.vector(level.mesh.positions);
    h.vector(level.mesh.normals);
    h.vector(level.mesh.triangles);
    h.vector(level.binding.joints);
    h.vector(level.binding.weights);
  }
  const bool muscles = options.muscles && rig.muscles && rig.muscles->set.point_count > 0;
  h.value(muscles);
  if (muscles) {
    h.value(rig.muscles->set.point_count);
    for (const auto& line : rig.muscles->set.lines) h.bytes(line.name.data(), line.name.size());
  }
  // Hashed only when not linear, so the linear atlases cached before skinning modes existed keep their key.
  if (options.skinning != SkinningMode::Linear) h.value(options.skinning);
  h.value(style);
  const ImpostorAtlasLayout& l = options.layout;
  h.value(l.phases), h.value(l.azimuths), h.value(l.elevations), h.value(l.max_elevation_deg);
  h.value(l.cell_width), h.value(l.cell_height);
  h.value(options.mesh_level), h.value(options.speed_m_s);
  return h.h;
}

ImpostorAtlas bake_impostor_atlas(const Rig& rig, const GaitStyle& style, const ImpostorBakeOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const ImpostorAtlasLayout& layout = options.layout;
  if (!layout.valid()) throw std::invalid_argument("impostor bake: invalid atlas layout");
  if (!rig.body || rig.body->levels.empty()) throw std::invalid_argument("impostor bake: the rig has no body");
  if (!(options.speed_m_s > 0.0f && std::isfinite(options.speed_m_s)))
    throw std::invalid_argument("impostor bake: the speed must be positive");

  // A private crowd of one walker on a long straight (a stadium whose straights are 2 km long).
  Crowd crowd(rig);
  if (!crowd.motion.locomotion) throw std::invalid_argument("impostor bake: the rig cannot walk: " + crowd.motion.walk_error);
  crowd.motion.style = style;
  crowd.motion.source = MotionSource::Walk;
  const int level = std::clamp(options.mesh_level, 0, static_cast<int>(rig.body->levels.size()) - 1);
  set_detail_level(crowd, DetailLevel::mesh(level));
  set_muscles_enabled(crowd, options.muscles);
  set_skinning_mode(crowd, options.skinning);
  set_paths(crowd, make_stadium_lanes(glm::vec3(0.0f), 2000.0f, 10.0f, 1, 1.0f));
  const float stature = crowd.motion.locomotion->rig_height;
  const float cadence = cadence_for_speed(options.speed_m_s, stature);
  spawn_walker(crowd, 0, 1.0f, 0.0f, stature, cadence, 0.0f, 0.0f, 0.0f);
  Profiler profiler(1, false);
  // Two cycles first, so the pelvis and feet are in their steady rhythm rather than the start's.
  for (int i = 0; i < 2 * 120; ++i) step(crowd, 1.0f / 60.0f, profiler);

  // Every phase's skinned body first (world space, the six attribute streams), with the walker's placement, so the
  // cells can be sized to what the walk really sweeps before anything is drawn.
  struct PhaseBody {
    std::array<std::vector<float>, 6> streams;
    Placement placement;
  };
  std::vector<PhaseBody> bodies(static_cast<std::size_t>(layout.phases));
  const SkinnedCrowd& skinned = crowd.skinned[static_cast<std::size_t>(level)];
  for (int k = 0; k < layout.phases; ++k) {
    walk_to_phase(crowd, static_cast<float>(k) / static_cast<float>(layout.phases), profiler);
    const SoaTable& t = crowd.table(mesh_slot(level));
    const float heading = t.f32(kWalkerPlacement, 3)[0];
    const glm::vec3 ground(t.f32(kWalkerPlacement, 0)[0], t.f32(kWalkerPlacement, 1)[0], t.f32(kWalkerPlacement, 2)[0]);
    PhaseBody& b = bodies[static_cast<std::size_t>(k)];
    b.placement = Placement{ground, std::cos(heading), std::sin(heading), 1.0f};
    const float* arrays[6] = {skinned.px.data(), skinned.py.data(), skinned.pz.data(),
                              skinned.nx.data(), skinned.ny.data(), skinned.nz.data()};
    for (int a = 0; a < 6; ++a)
      b.streams[static_cast<std::size_t>(a)].assign(arrays[a], arrays[a] + skinned.vertex_count);
  }

  ImpostorAtlas atlas;
  atlas.layout = layout;
  atlas.center_height_m = 0.5f * crowd.skin.body_height;
  atlas.speed_m_s = options.speed_m_s;
  // Cell size and depth range: the largest extent of the body, over every phase and every atlas direction, along
  // the cell's right and up axes and the view axis, plus 4 %. Fixed fractions of the stature were tried first and
  // cut the feet off in side views at long strides (the test that every walker clears its cell's edge).
  auto direction = [&](int a, int e) {
    const float elevation = layout.elevations > 1 ? glm::radians(layout.max_elevation_deg) * static_cast<float>(e) /
                                                        static_cast<float>(layout.elevations - 1)
                                                  : 0.0f;
    const float azimuth = 6.28318530718f * static_cast<float>(a) / static_cast<float>(layout.azimuths);
    return glm::vec3(std::sin(azimuth) * std::cos(elevation), std::sin(elevation), std::cos(azimuth) * std::cos(elevation));
  };
  float half_width = 0.0f, half_height = 0.0f, depth = 0.0f;
  for (const PhaseBody& b : bodies) {
    const glm::vec3 center = b.placement.position + glm::vec3(0.0f, atlas.center_height_m, 0.0f);
    for (int e = 0; e < layout.elevations; ++e)
      for (int a = 0; a < layout.azimuths; ++a) {
        const glm::vec3 d = b.placement.direction(direction(a, e));
        const glm::vec3 right = glm::normalize(glm::cross(glm::vec3(0.0f, 1.0f, 0.0f), d));
        const glm::vec3 up = glm::cross(d, right);
        for (std::size_t v = 0; v < b.streams[0].size(); ++v) {
          const glm::vec3 p = glm::vec3(b.streams[0][v], b.streams[1][v], b.streams[2][v]) - center;
          half_width = std::max(half_width, std::abs(glm::dot(p, right)));
          half_height = std::max(half_height, std::abs(glm::dot(p, up)));
          depth = std::max(depth, std::abs(glm::dot(p, d)));
        }
      }
  }
  atlas.cell_width_m = 2.0f * 1.04f * half_width;
  atlas.cell_height_m = 2.0f * 1.04f * half_height;
  atlas.depth_range_m = 1.04f * depth;
  atlas.key = impostor_atlas_key(rig, style, options);
  const std::size_t layer_bytes = layout.layer_bytes();
  atlas.color.resize(layer_bytes * static_cast<std::size_t>(layout.phases));
  atlas.normal_depth.resize(atlas.color.size());

  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  const int samples = max_samples >= 4 ? 4 : 0;
  const int W = layout.layer_width(), H = layout.layer_height();
  BakeTarget msaa(W, H, samples);
  BakeTarget resolved(W, H, 0);
  GlObject program = link_program("render/shaders/body.vert", shader_source("render/shaders/body.vert"),
                                  "render/shaders/impostor_bake.frag",
                                  shader_source("render/shaders/impostor_bake.frag"));
  GlObject vao(GlKind::kVertexArray), components(GlKind::kBuffer), indices(GlKind::kBuffer);
  const GLuint p = program.id();
  for (GLuint a = 0; a < 6; ++a) {
    glEnableVertexArrayAttrib(vao.id(), a);
    glVertexArrayAttribFormat(vao.id(), a, 1, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao.id(), a, a);
  }
  const std::vector<std::uint32_t>& triangles = crowd.skin.layouts[static_cast<std::size_t>(level)].triangles;
  glNamedBufferData(indices.id(), static_cast<GLsizeiptr>(triangles.size() * sizeof(std::uint32_t)), triangles.data(),
                    GL_STATIC_DRAW);
  glVertexArrayElementBuffer(vao.id(), indices.id());

  // GL state the bake depends on; restored to what the renderer's frames set up themselves (begin_frame).
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glDisable(GL_SAMPLE_ALPHA_TO_COVERAGE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glUseProgram(p);
  glProgramUniform1f(p, glGetUniformLocation(p, "u_depth_range"), atlas.depth_range_m);
  glVertexAttrib4f(6, 0.0f, 0.0f, 0.0f, 0.0f);
  // The dress weights of each vertex (the top, the bottom with the shoes, hair; skin the rest) as body.vert's
  // per-vertex colour, the same for every phase: the impostor shader mixes the walker's palette by them.
  GlObject dress(GlKind::kBuffer);
  {
    const SkinLayout& layout = crowd.skin.layouts[static_cast<std::size_t>(level)];
    std::vector<std::uint32_t> weights(layout.vertex_count, 0xff000000u);
    if (rig.body && level < static_cast<int>(rig.body->levels.size())) {
      const SurfaceClasses classes = layout_materials(rig.body->levels[static_cast<std::size_t>(level)].mesh, layout);
      for (std::size_t v = 0; v < classes.size() && v < weights.size(); ++v) {
        const SurfaceMaterial m = classes.at(v);
        const unsigned byte = m == SurfaceMaterial::Top                                    ? 0u
                              : m == SurfaceMaterial::Bottom || m == SurfaceMaterial::Shoes ? 8u
                              : m == SurfaceMaterial::Hair                                  ? 16u
                                                                                            : 32u;
        if (byte < 32u) weights[v] |= 0xffu << byte;
      }
    }
    glNamedBufferData(dress.id(), static_cast<GLsizeiptr>(weights.size() * sizeof(std::uint32_t)), weights.data(),
                      GL_STATIC_DRAW);
    glVertexArrayAttribFormat(vao.id(), 7, 4, GL_UNSIGNED_BYTE, GL_TRUE, 0);
    glVertexArrayAttribBinding(vao.id(), 7, 7);
    glVertexArrayVertexBuffer(vao.id(), 7, dress.id(), 0, sizeof(std::uint32_t));
    glEnableVertexArrayAttrib(vao.id(), 7);
  }
  const float distance = 2.0f * atlas.depth_range_m + 1.0f;
  const glm::mat4 projection = glm::ortho(-0.5f * atlas.cell_width_m, 0.5f * atlas.cell_width_m,
                                          -0.5f * atlas.cell_height_m, 0.5f * atlas.cell_height_m,
                                          distance - atlas.depth_range_m, distance + atlas.depth_range_m);
  glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_projection"), 1, GL_FALSE, glm::value_ptr(projection));
  glProgramUniform1f(p, glGetUniformLocation(p, "u_center_z"), -distance);
  const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  const float far_depth = 1.0f;
  for (int k = 0; k < layout.phases; ++k) {
    const PhaseBody& body = bodies[static_cast<std::size_t>(k)];
    const Placement& placement = body.placement;
    const glm::vec3 center = placement.position + glm::vec3(0.0f, atlas.center_height_m, 0.0f);
    // This phase's skinned body (world space) as the six attribute streams.
    const std::size_t n = body.streams[0].size();
    const GLsizeiptr bytes = static_cast<GLsizeiptr>(n * sizeof(float));
    glNamedBufferData(components.id(), 6 * bytes, nullptr, GL_STREAM_DRAW);
    for (GLuint a = 0; a < 6; ++a) {
      glNamedBufferSubData(components.id(), a * bytes, bytes, body.streams[a].data());
      glVertexArrayVertexBuffer(vao.id(), a, components.id(), a * bytes, sizeof(float));
    }
    glBindFramebuffer(GL_FRAMEBUFFER, msaa.fbo.id());
    glViewport(0, 0, W, H);
    glClearNamedFramebufferfv(msaa.fbo.id(), GL_COLOR, 0, zero);
    glClearNamedFramebufferfv(msaa.fbo.id(), GL_COLOR, 1, zero);
    glClearNamedFramebufferfv(msaa.fbo.id(), GL_DEPTH, 0, &far_depth);
    glBindVertexArray(vao.id());
    for (int e = 0; e < layout.elevations; ++e) {
      for (int a = 0; a < layout.azimuths; ++a) {
        const glm::vec3 d = placement.direction(direction(a, e));
        const glm::mat4 view = glm::lookAt(center + distance * d, center, glm::vec3(0.0f, 1.0f, 0.0f));
        // view space -> world (the view's rotation transposed) -> the walker's frame (heading undone).
        const glm::mat3 world_to_local(glm::vec3(placement.cos_heading, 0.0f, placement.sin_heading),
                                       glm::vec3(0.0f, 1.0f, 0.0f),
                                       glm::vec3(-placement.sin_heading, 0.0f, placement.cos_heading));
        const glm::mat3 view_to_local = world_to_local * glm::transpose(glm::mat3(view));
        glProgramUniformMatrix4fv(p, glGetUniformLocation(p, "u_view"), 1, GL_FALSE, glm::value_ptr(view));
        glProgramUniformMatrix3fv(p, glGetUniformLocation(p, "u_view_to_local"), 1, GL_FALSE,
                                  glm::value_ptr(view_to_local));
        glViewport(a * layout.cell_width, e * layout.cell_height, layout.cell_width, layout.cell_height);
        glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(triangles.size()), GL_UNSIGNED_INT, nullptr);
      }
    }
    // Resolve each attachment, then read the layer back.
    for (GLenum attachment : {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1}) {
      glNamedFramebufferReadBuffer(msaa.fbo.id(), attachment);
      glNamedFramebufferDrawBuffer(resolved.fbo.id(), attachment);
      glBlitNamedFramebuffer(msaa.fbo.id(), resolved.fbo.id(), 0, 0, W, H, 0, 0, W, H, GL_COLOR_BUFFER_BIT,
                             GL_NEAREST);
    }
    glBindFramebuffer(GL_READ_FRAMEBUFFER, resolved.fbo.id());
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    const std::size_t offset = static_cast<std::size_t>(k) * layer_bytes;
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, W, H, GL_RGBA, GL_UNSIGNED_BYTE, atlas.color.data() + offset);
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, W, H, GL_RGBA, GL_UNSIGNED_BYTE, atlas.normal_depth.data() + offset);
  }
  glBindVertexArray(0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (const GLenum error = glGetError(); error != GL_NO_ERROR) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "impostor bake: GL error 0x%04X", static_cast<unsigned>(error));
    throw std::runtime_error(buf);
  }
  atlas.bake_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return atlas;
}

ImpostorAtlas load_or_bake_impostor_atlas(const Rig& rig, const GaitStyle& style, const ImpostorBakeOptions& options,
                                          const std::optional<std::filesystem::path>& cache_directory) {
  const std::uint64_t key = impostor_atlas_key(rig, style, options);
  char name[64];
  std::snprintf(name, sizeof name, "impostor-%016llx.bin", static_cast<unsigned long long>(key));
  if (cache_directory)
    if (std::optional<ImpostorAtlas> cached = load_impostor_atlas(*cache_directory / name, key)) return std::move(*cached);
  ImpostorAtlas atlas = bake_impostor_atlas(rig, style, options);
  if (cache_directory) save_impostor_atlas(*cache_directory / name, atlas);
  return atlas;
}

const ImpostorAtlas* ensure_impostor_atlas(Crowd& crowd) {
  if (!crowd_may_use_impostors(crowd)) return nullptr;
  if (crowd.impostor_atlas) return crowd.impostor_atlas.get();
  ImpostorBakeOptions options;
  options.muscles = crowd.muscles_enabled();
  options.skinning = crowd.skin.mode;
  // The crowd's mean lane speed, rounded to 0.1 m/s so crowds that differ a little share one cached atlas.
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    const SoaTable& t = crowd.world.table(crowd.tables[s]);
    for (const float v : t.f32(kWalkerGait, kGaitBaseSpeed).first(t.size()))
      if (v > 0.0f) sum += v, ++n;
  }
  if (n > 0) options.speed_m_s = std::max(0.5f, std::round(static_cast<float>(sum / static_cast<double>(n)) * 10.0f) / 10.0f);
  crowd.impostor_atlas = std::make_shared<const ImpostorAtlas>(
      load_or_bake_impostor_atlas(crowd.rig(), crowd.motion.style, options, body_cache_directory()));
  return crowd.impostor_atlas.get();
}

}  // namespace strata
