#include "render/crowd_renderer.h"

#include <epoxy/gl.h>

#include <cmath>
#include <limits>
#include <optional>
#include <variant>
#include <stdexcept>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "profiling/profiler.h"
#include "render/body_pass.h"
#include "render/ground_pass.h"
#include "render/impostor_pass.h"
#include "render/props_pass.h"
#include "render/reference_pass.h"
#include "render/render_target.h"
#include "render/ray_tracer.h"
#include "render/shadow_pass.h"
#include "render/skeleton_pass.h"
#include "systems/pose_gather.h"

namespace strata {

namespace {

// The sun and sky of RenderQuality::High. Linear values, balanced so that a surface facing the sun is about three
// times as bright as one lit by the sky alone: a clear afternoon, with shadows that read without going black.
Sunlight sunlight(const RenderOptions& o) {
  Sunlight s;
  const float length = glm::length(o.to_sun);
  s.to_sun = length > 1e-6f && std::isfinite(length) ? o.to_sun / length : glm::vec3(0.0f, 1.0f, 0.0f);
  s.sun_color = glm::vec3(2.3f, 2.18f, 1.98f);
  s.sky_color = glm::vec3(0.42f, 0.50f, 0.66f);
  s.bounce_color = glm::vec3(0.20f, 0.18f, 0.15f);
  s.exposure = 0.8f;
  return s;
}

// Times the passes of a frame under one profiler scope each (set_profiler): each pass's GL commands are finished
// before its scope ends, so the scope holds the pass's own cost rather than whichever later call waited for it.
// Without a profiler it does nothing and the frame runs without those waits.
class PassTimer {
 public:
  explicit PassTimer(Profiler* profiler) : profiler_(profiler) {}
  ~PassTimer() { stop(); }
  void start(const char* name) {
    if (!profiler_) return;
    stop();
    scope_.emplace(*profiler_, profiler_->intern(name));
  }
  void stop() {
    if (!scope_) return;
    glFinish();
    scope_.reset();
  }

 private:
  Profiler* profiler_;
  std::optional<Profiler::ScopedTimer> scope_;
};

}  // namespace

struct CrowdRenderer::Impl {
  Impl(int width, int height, const RenderOptions& o) : options(o), target(width, height) {}

  RenderOptions options;
  RenderTarget target;
  SkeletonPass skeleton;
  BodyPass body;
  GroundPass ground;
  PropsPass props;
  std::optional<ReferencePass> reference;  // built on the benchmark's first call
  std::optional<ShadowPass> shadow;        // built on the first RenderQuality::High frame
  std::optional<RayTracer> tracer;         // built on the first RenderBackend::RayTraced frame
  std::vector<std::uint8_t> traced;        // that frame's image, which read_rgba() returns
  bool last_traced = false;
  std::vector<PropVertex> props_cpu;       // the props as given, for the ray tracer
  std::uint64_t props_cpu_key = 0;
  Profiler* profiler = nullptr;
  std::size_t triangles_drawn = 0;
  std::vector<glm::vec3> ground_points;  // scratch

  // What the ground fits its extent to: the drawn joints and the impostors' feet together (only frames with
  // impostors pay for the copy).
  std::span<const glm::vec3> ground_fit_points(const SkeletonDrawInput& input) {
    std::span<const glm::vec3> points = drawn_joint_positions(input);
    if (input.ground_points.empty()) return points;
    ground_points.assign(points.begin(), points.end());
    ground_points.insert(ground_points.end(), input.ground_points.begin(), input.ground_points.end());
    return ground_points;
  }
  std::vector<glm::vec3> casters;        // scratch
  PixelRect footprint;
};

namespace {

// The box of the bodies' finite vertices (for bodies drawn without skeletons); lo > hi when there are none.
void body_vertex_bounds(const BodySource& bodies, glm::vec3& lo, glm::vec3& hi) {
  lo = glm::vec3(std::numeric_limits<float>::max()), hi = glm::vec3(std::numeric_limits<float>::lowest());
  for (std::size_t k = 0; k < bodies.batch_count(); ++k)
    if (const BodyBatch batch = bodies.batch(k); const BodyDrawInput* b = std::get_if<BodyDrawInput>(&batch))
      for (std::size_t w = 0; w < b->walker_count; ++w)
        for (std::size_t v = 0; v < b->vertex_count; ++v) {
          const std::size_t i = w * b->stride + v;
          const glm::vec3 p(b->px[i], b->py[i], b->pz[i]);
          if (std::isfinite(p.x + p.y + p.z)) lo = glm::min(lo, p), hi = glm::max(hi, p);
        }
}

// How far a body reaches past its joints (hands past the wrists, the crown past the skull base, flesh around
// the bones): what the shadow frustum and the footprint grow the joints' box by.
constexpr float kBodyReach = 0.35f;

// [lo, hi] grown by every impostor batch's quads.
void grow_by_impostor_batches(const BodySource& bodies, glm::vec3& lo, glm::vec3& hi) {
  for (std::size_t k = 0; k < bodies.batch_count(); ++k) {
    const BodyBatch batch = bodies.batch(k);
    if (const ImpostorBatch* b = std::get_if<ImpostorBatch>(&batch)) grow_by_impostors(*b, lo, hi);
  }
}

// The box of what a frame draws of walkers: the joints grown by a body's reach (or, for bodies without
// skeletons, their vertices), and `impostors`, the impostors' quads (grow_by_impostor_batches).
void walker_bounds(const SkeletonDrawInput& input, const BodySource& bodies, const glm::vec3& impostors_lo,
                   const glm::vec3& impostors_hi, glm::vec3& lo, glm::vec3& hi) {
  const std::span<const glm::vec3> joints = drawn_joint_positions(input);
  if (joint_bounds(joints, lo, hi)) {
    lo -= glm::vec3(kBodyReach), hi += glm::vec3(kBodyReach);
  } else if (joints.empty()) {
    body_vertex_bounds(bodies, lo, hi);
  }
  lo = glm::min(lo, impostors_lo), hi = glm::max(hi, impostors_hi);
}

}  // namespace

CrowdRenderer::CrowdRenderer(int width, int height, RenderOptions options)
    : impl_(std::make_unique<Impl>(width, height, options)) {}

CrowdRenderer::~CrowdRenderer() = default;

int CrowdRenderer::width() const { return impl_->target.width(); }
int CrowdRenderer::height() const { return impl_->target.height(); }
RenderOptions& CrowdRenderer::options() { return impl_->options; }
void CrowdRenderer::set_profiler(Profiler* profiler) { impl_->profiler = profiler; }
void CrowdRenderer::resize(int width, int height) { impl_->target.resize(width, height); }
std::size_t CrowdRenderer::triangles_drawn() const { return impl_->triangles_drawn; }
std::size_t CrowdRenderer::impostors_drawn() const { return impl_->body.impostors_drawn(); }
void CrowdRenderer::set_props(std::uint64_t key, std::span<const PropVertex> triangles) {
  if (triangles.empty()) impl_->props.clear();
  else impl_->props.upload(key, triangles);
  impl_->props_cpu.assign(triangles.begin(), triangles.end());
  impl_->props_cpu_key = triangles.empty() ? 0 : key;
}
std::uint64_t CrowdRenderer::props_key() const { return impl_->props.empty() ? 0 : impl_->props.key(); }

void CrowdRenderer::render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
                           const BodyDrawInput* bodies) {
  render(input, view, projection,
         bodies ? std::span<const BodyDrawInput>(bodies, 1) : std::span<const BodyDrawInput>());
}

void CrowdRenderer::render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
                           std::span<const BodyDrawInput> body_levels) {
  render(input, view, projection, CpuSkinnedBodies(body_levels));
}

void CrowdRenderer::render(const SkeletonDrawInput& input, const glm::mat4& view, const glm::mat4& projection,
                           const BodySource& bodies) {
  Impl& r = *impl_;
  if (r.options.backend == RenderBackend::RayTraced) {
    // The ray tracer checks its own inputs first; it draws bodies, props and ground, never skeletons.
    if (!r.tracer) r.tracer.emplace();
    r.tracer->set_props(r.props_cpu_key, r.props_cpu);
    r.tracer->render(bodies, r.ground_fit_points(input), view, projection, r.options, r.target.width(), r.target.height(), r.traced,
                     r.profiler);
    r.triangles_drawn = r.tracer->triangles_traced();
    r.last_traced = true;
    r.footprint = PixelRect{0, 0, r.target.width(), r.target.height()};
    return;
  }
  r.last_traced = false;
  // Every input is checked before the frame starts, so a bad one throws with the last image intact. Then ground,
  // skeletons, bodies: the order the single-file renderer drew in, which the frames' bytes depend on where
  // depth ties (a joint sphere and a body surface at the same depth keep whichever came first, GL_LESS).
  r.body.check(bodies);
  check_skeleton_input(input);
  const RenderOptions& o = r.options;
  PassTimer timer(r.profiler);
  // The impostors' quads: the shadow frustum holds them, and so does the frame's footprint.
  glm::vec3 imp_lo(std::numeric_limits<float>::max()), imp_hi(std::numeric_limits<float>::lowest());
  grow_by_impostor_batches(bodies, imp_lo, imp_hi);
  // RenderQuality::High: the sun's shadow map first, from the bodies' vertices as this frame streams them (the
  // colour pass below draws from the same buffers) and the props; its frustum fits the joints, grown by how far
  // a body reaches past them.
  Sunlight sun;
  ShadedFrame shaded;
  const bool high = o.quality == RenderQuality::High;
  if (high) {
    timer.start("shadow_map");
    if (!r.shadow) r.shadow.emplace();
    sun = sunlight(o);
    shaded.shadow = &*r.shadow;
    shaded.sun = &sun;
    shaded.eye = glm::vec3(glm::inverse(view)[3]);
    std::span<const glm::vec3> casters = drawn_joint_positions(input);
    // Impostors cast shadows too (render/impostor_pass.h): the frustum holds their quads.
    if (!input.shadow_fit_points.empty() || imp_lo.x <= imp_hi.x) {
      r.casters.assign(casters.begin(), casters.end());
      r.casters.insert(r.casters.end(), input.shadow_fit_points.begin(), input.shadow_fit_points.end());
      if (imp_lo.x <= imp_hi.x) r.casters.insert(r.casters.end(), {imp_lo, imp_hi});
      casters = r.casters;
    }
    if (casters.empty()) {
      // Bodies without skeletons (a caller drawing meshes only): the corners of their vertices' bounds.
      glm::vec3 lo, hi;
      body_vertex_bounds(bodies, lo, hi);
      r.casters.assign({lo, hi});
      if (lo.x <= hi.x) casters = r.casters;
    }
    shaded.shadows = r.shadow->begin(sun.to_sun, casters, kBodyReach);
    if (shaded.shadows) {
      r.body.draw_shadow(bodies, *r.shadow);
      r.props.draw_shadow(*r.shadow);
      r.shadow->end();
    }
  }
  timer.start("ground");
  r.target.begin_frame(o.clear_color);
  if (o.draw_ground) {
    r.ground.draw(r.ground_fit_points(input), view, projection, o.ground_color, o.clear_color, high ? &shaded : nullptr);
  }
  r.props.draw(view, projection, high ? &shaded : nullptr);
  timer.start("skeletons");
  if (o.draw_skeleton) r.skeleton.draw(input, view, projection, o);
  timer.start("bodies");
  r.body.draw(bodies, view, projection, o.skin_color, high ? &shaded : nullptr);
  r.triangles_drawn = r.body.triangles_drawn();
  glBindVertexArray(0);  // no VAO of ours stays bound for GL the caller draws next (the viewer's panel)
  timer.start("resolve");
  r.target.resolve();
  timer.stop();
  glm::vec3 lo, hi;
  walker_bounds(input, bodies, imp_lo, imp_hi, lo, hi);
  if (shaded.shadows) {
    // The filtered lookup and its normal offset spread a shadow's edge by about two and a half texels.
    const float spread = 3.0f * r.shadow->texel_world();
    lo -= glm::vec3(spread, 0.0f, spread), hi += glm::vec3(spread, 0.0f, spread);
  }
  r.footprint = screen_footprint(lo, hi, shaded.shadows ? &sun.to_sun : nullptr, projection * view, r.target.width(),
                                 r.target.height());
}

void CrowdRenderer::render_instanced_reference(const BodyDrawInput& mesh, std::span<const glm::vec3> offsets,
                                               const glm::mat4& view, const glm::mat4& projection) {
  Impl& r = *impl_;
  if (!r.reference) r.reference.emplace();
  r.reference->upload(mesh, offsets);
  r.target.begin_frame(r.options.clear_color);
  r.triangles_drawn = r.reference->draw(view, projection, r.options.skin_color);
  r.footprint = PixelRect{0, 0, r.target.width(), r.target.height()};
  glBindVertexArray(0);
  r.target.resolve();
}

PixelRect CrowdRenderer::last_footprint() const { return impl_->footprint; }
void CrowdRenderer::finish() const { glFinish(); }
void CrowdRenderer::read_rgba(std::vector<std::uint8_t>& out) const {
  if (impl_->last_traced) out = impl_->traced;
  else impl_->target.read_rgba(out);
}
void CrowdRenderer::read_depth(std::vector<float>& out) const {
  if (impl_->last_traced) throw std::logic_error("crowd renderer: a ray-traced frame has no depth buffer");
  impl_->target.read_depth(out);
}
unsigned CrowdRenderer::output_framebuffer() const { return impl_->target.output_framebuffer(); }
void CrowdRenderer::blit_to_default_framebuffer(int width, int height) const {
  impl_->target.blit_to_default_framebuffer(width, height);
}

}  // namespace strata
