#include "rig/binding_editor.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/matrix.hpp>

#include "io/atomic_file.h"
#include "io/load_error.h"

namespace strata {
namespace {

// A vertex counts as visible when it is at most this fraction of its distance from the camera behind the nearest
// surface sampled around it. The 2x2 sampling below already keeps a vertex on a locally flat surface visible
// with no tolerance at all (see visible_vertices); this covers creases and rounding. 0.5 % is 1.5 cm at 3 m:
// far less than a torso (the body's back is 15+ cm behind its front) or a limb, more than the curvature error
// of a crease one pixel wide. An absolute tolerance was rejected: it would be too tight far away and too loose
// in a close-up.
constexpr double kRelativeDepthTolerance = 5e-3;

void check_viewport(glm::ivec2 viewport) {
  if (viewport.x <= 0 || viewport.y <= 0)
    throw std::invalid_argument("binding editor: viewport " + std::to_string(viewport.x) + "x" +
                                std::to_string(viewport.y) + " is empty");
}

void check_indices(const EditMesh& mesh) {
  if (mesh.triangles.size() % 3 != 0)
    throw std::invalid_argument("binding editor: triangle index count is not a multiple of 3");
  for (std::uint32_t i : mesh.triangles)
    if (i >= mesh.positions.size())
      throw std::invalid_argument("binding editor: triangle index " + std::to_string(i) + " but the mesh has " +
                                  std::to_string(mesh.positions.size()) + " vertices");
}

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(const glm::dvec4& v) { return finite(glm::dvec3(v)) && std::isfinite(v.w); }

// Clip-space position (double: the near-plane and depth arithmetic below divides by w).
glm::dvec4 to_clip(const glm::dmat4& view_projection, const glm::vec3& p) {
  return view_projection * glm::dvec4(glm::dvec3(p), 1.0);
}

// Pixel position (x right, y down, continuous) and NDC depth of a clip-space point with w > 0.
glm::dvec3 to_screen(const glm::dvec4& clip, glm::ivec2 viewport) {
  const glm::dvec3 ndc = glm::dvec3(clip) / clip.w;
  return {(ndc.x + 1.0) * 0.5 * viewport.x, (1.0 - ndc.y) * 0.5 * viewport.y, ndc.z};
}

// Where a vertex lands on screen, when it is in front of the camera (between the near and far planes), finite,
// and inside the viewport; what box, brush and visibility agree on as "on screen".
std::optional<glm::dvec3> on_screen(const glm::dmat4& view_projection, const glm::vec3& p, glm::ivec2 viewport) {
  const glm::dvec4 c = to_clip(view_projection, p);
  if (!finite(c) || !(c.w > 0.0) || c.z < -c.w || c.z > c.w) return std::nullopt;
  const glm::dvec3 s = to_screen(c, viewport);
  if (!(s.x >= 0.0 && s.x <= viewport.x && s.y >= 0.0 && s.y <= viewport.y)) return std::nullopt;
  return s;
}

void check_selection_sizes(const EditMesh& mesh, std::span<const std::uint8_t> visible,
                           const VertexSelection& selection) {
  if (selection.vertex_count() != mesh.positions.size() || (!visible.empty() && visible.size() != mesh.positions.size()))
    throw std::invalid_argument("binding editor: the mesh has " + std::to_string(mesh.positions.size()) +
                                " vertices, the selection " + std::to_string(selection.vertex_count()) +
                                " and the visibility mask " + std::to_string(visible.size()));
}

// Applies `op` to every on-screen (and, unless `visible` is empty, visible) vertex for which inside(x, y) holds.
template <class Inside>
void select_where(const EditMesh& mesh, const glm::mat4& view_projection, glm::ivec2 viewport,
                  std::span<const std::uint8_t> visible, SelectOp op, VertexSelection& selection, Inside inside) {
  check_viewport(viewport);
  check_selection_sizes(mesh, visible, selection);
  if (op == SelectOp::Replace) selection.clear();
  const glm::dmat4 vp(view_projection);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    if (!visible.empty() && !visible[v]) continue;
    const std::optional<glm::dvec3> s = on_screen(vp, mesh.positions[v], viewport);
    if (!s || !inside(s->x, s->y)) continue;
    selection.set(static_cast<std::uint32_t>(v), op != SelectOp::Subtract);
  }
}

// Software depth buffer: NDC depth per pixel centre, the nearest surface; +inf where nothing is drawn. NDC depth
// is affine in screen space for perspective and orthographic cameras alike, so plain screen-space barycentrics
// interpolate it exactly (view-space depth would need perspective-correct 1/w interpolation).
class DepthBuffer {
 public:
  explicit DepthBuffer(glm::ivec2 size)
      : size_(size), depth_(static_cast<std::size_t>(size.x) * static_cast<std::size_t>(size.y),
                            std::numeric_limits<float>::infinity()) {}

  // Draws the triangle after clipping it against the near plane (z >= -w): a triangle reaching behind the camera
  // still hides what is behind its visible part. Skipping such triangles was rejected: a close-up would then see
  // through every triangle that crosses the near plane.
  void draw(const glm::dvec4 (&clip)[3]) {
    std::array<glm::dvec4, 4> poly;
    std::size_t n = 0;
    for (int k = 0; k < 3; ++k) {
      const glm::dvec4& a = clip[k];
      const glm::dvec4& b = clip[(k + 1) % 3];
      const double da = a.z + a.w, db = b.z + b.w;  // >= 0 in front of the near plane
      if (da >= 0.0) poly[n++] = a;
      if ((da >= 0.0) != (db >= 0.0)) poly[n++] = a + (b - a) * (da / (da - db));
    }
    if (n < 3) return;
    std::array<glm::dvec3, 4> screen;
    for (std::size_t k = 0; k < n; ++k) {
      if (!(poly[k].w > 0.0)) return;  // on the eye plane: only possible for a degenerate projection
      screen[k] = to_screen(poly[k], size_);
    }
    for (std::size_t k = 1; k + 1 < n; ++k) fill(screen[0], screen[k], screen[k + 1]);
  }

  // The farthest of the (up to) four pixel centres around screen point (x, y): a vertex is hidden only when all
  // of them show something nearer. For a locally flat surface through the vertex, depth is affine in screen
  // space, so over the square of four centres around the vertex its maximum is at least the vertex's own depth:
  // the vertex's own triangles never hide it. The single nearest pixel centre was rejected: on a surface seen
  // at a grazing angle (near a silhouette) its depth is nearer than the vertex by the slope times half a pixel.
  double farthest_around(double x, double y) const {
    const int x0 = static_cast<int>(std::floor(x - 0.5)), y0 = static_cast<int>(std::floor(y - 0.5));
    double far = -std::numeric_limits<double>::infinity();
    for (int dy = 0; dy <= 1; ++dy)
      for (int dx = 0; dx <= 1; ++dx) {
        const int px = std::clamp(x0 + dx, 0, size_.x - 1), py = std::clamp(y0 + dy, 0, size_.y - 1);
        far = std::max(far, static_cast<double>(depth_[index(px, py)]));
      }
    return far;
  }

 private:
  std::size_t index(int x, int y) const {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(size_.x) + static_cast<std::size_t>(x);
  }

  void fill(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    const double area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if (!(std::abs(area) > 0.0) || !std::isfinite(area)) return;  // edge-on, degenerate or non-finite
    // Pixel centres (i + 0.5, j + 0.5) inside the bounding box, clamped in double before converting to int so a
    // vertex far off screen cannot overflow.
    auto first = [](double lo, int size) {
      return static_cast<int>(std::clamp(std::ceil(lo - 0.5), 0.0, static_cast<double>(size)));
    };
    auto last = [](double hi, int size) {
      return static_cast<int>(std::clamp(std::floor(hi - 0.5), -1.0, static_cast<double>(size - 1)));
    };
    const int x_lo = first(std::min({a.x, b.x, c.x}), size_.x), x_hi = last(std::max({a.x, b.x, c.x}), size_.x);
    const int y_lo = first(std::min({a.y, b.y, c.y}), size_.y), y_hi = last(std::max({a.y, b.y, c.y}), size_.y);
    const double inv_area = 1.0 / area;
    for (int y = y_lo; y <= y_hi; ++y) {
      const double py = y + 0.5;
      for (int x = x_lo; x <= x_hi; ++x) {
        const double px = x + 0.5;
        // Barycentric weights, each the signed area opposite a corner over the whole; all >= 0 inside (edges
        // included: a pixel centre on a shared edge is drawn by both triangles, harmless for a depth buffer).
        const double wa = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) * inv_area;
        const double wb = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) * inv_area;
        const double wc = 1.0 - wa - wb;
        if (wa < 0.0 || wb < 0.0 || wc < 0.0) continue;
        const float z = static_cast<float>(wa * a.z + wb * b.z + wc * c.z);
        float& d = depth_[index(x, y)];
        d = std::min(d, z);
      }
    }
  }

  glm::ivec2 size_;
  std::vector<float> depth_;
};

// The heat ramp's stops, evenly spaced: blue, green, yellow, red.
constexpr std::array<glm::dvec3, 4> kHeatStops = {glm::dvec3(0, 0, 255), glm::dvec3(0, 255, 0),
                                                   glm::dvec3(255, 255, 0), glm::dvec3(255, 0, 0)};

std::uint32_t pack_rgba(const glm::dvec3& rgb) {
  auto byte = [](double c) { return static_cast<std::uint32_t>(std::lround(std::clamp(c, 0.0, 255.0))); };
  return byte(rgb.r) | byte(rgb.g) << 8 | byte(rgb.b) << 16 | 0xFFu << 24;
}

}  // namespace

PickRay pick_ray(const glm::mat4& view_projection, glm::vec2 pixel, glm::ivec2 viewport) {
  check_viewport(viewport);
  const glm::dmat4 vp(view_projection);
  const double det = glm::determinant(vp);
  if (!std::isfinite(det) || det == 0.0)
    throw std::invalid_argument("pick_ray: the view-projection matrix is singular or not finite");
  const glm::dmat4 inverse = glm::inverse(vp);
  const double x = 2.0 * pixel.x / viewport.x - 1.0, y = 1.0 - 2.0 * pixel.y / viewport.y;
  // The near and far plane points of the pixel; double keeps the far point exact enough at a far/near ratio of
  // 10^4 (the orbit camera's 500 m / 0.05 m), where float would lose the direction's low bits.
  const glm::dvec4 near_h = inverse * glm::dvec4(x, y, -1.0, 1.0), far_h = inverse * glm::dvec4(x, y, 1.0, 1.0);
  const glm::dvec3 near_p = glm::dvec3(near_h) / near_h.w, far_p = glm::dvec3(far_h) / far_h.w;
  const glm::dvec3 dir = far_p - near_p;
  const double len = glm::length(dir);
  if (!finite(near_p) || !finite(far_p) || !(len > 0.0) || !std::isfinite(len))
    throw std::invalid_argument("pick_ray: the view-projection matrix gives no ray through this pixel");
  return {glm::vec3(near_p), glm::vec3(dir / len)};
}

std::optional<std::uint32_t> pick_vertex(const EditMesh& mesh, const PickRay& ray) {
  check_indices(mesh);
  const glm::dvec3 o(ray.origin), d(ray.direction);
  if (!finite(o) || !finite(d) || !(glm::length(d) > 0.0)) return std::nullopt;
  double best_t = std::numeric_limits<double>::infinity();
  std::optional<std::uint32_t> best;
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const std::uint32_t idx[3] = {mesh.triangles[t], mesh.triangles[t + 1], mesh.triangles[t + 2]};
    const glm::dvec3 p0(mesh.positions[idx[0]]), p1(mesh.positions[idx[1]]), p2(mesh.positions[idx[2]]);
    if (!finite(p0) || !finite(p1) || !finite(p2)) continue;
    // Moller-Trumbore: solve o + t d = p0 + u e1 + v e2.
    const glm::dvec3 e1 = p1 - p0, e2 = p2 - p0;
    // Degenerate (zero-area, up to rounding relative to the edge lengths): no surface to hit, and the solve
    // below would divide by ~0.
    const double scale = glm::dot(e1, e1) * glm::dot(e2, e2);
    if (!(glm::dot(glm::cross(e1, e2), glm::cross(e1, e2)) > 1e-12 * scale)) continue;
    const glm::dvec3 q = glm::cross(d, e2);
    const double det = glm::dot(e1, q);
    if (std::abs(det) < 1e-300) continue;  // ray parallel to the triangle's plane
    const double inv = 1.0 / det;
    const glm::dvec3 s = o - p0;
    const double u = glm::dot(s, q) * inv;
    if (u < 0.0 || u > 1.0) continue;
    const glm::dvec3 r = glm::cross(s, e1);
    const double v = glm::dot(d, r) * inv;
    if (v < 0.0 || u + v > 1.0) continue;
    const double hit_t = glm::dot(e2, r) * inv;
    if (!(hit_t >= 0.0) || hit_t >= best_t) continue;
    best_t = hit_t;
    const glm::dvec3 hit = o + hit_t * d;
    int corner = 0;
    double corner_d = std::numeric_limits<double>::infinity();
    const glm::dvec3 corners[3] = {p0, p1, p2};
    for (int k = 0; k < 3; ++k)
      if (const double dk = glm::length(corners[k] - hit); dk < corner_d) corner = k, corner_d = dk;
    best = idx[corner];
  }
  return best;
}

std::vector<std::uint8_t> visible_vertices(const EditMesh& mesh, const glm::mat4& view_projection,
                                           glm::ivec2 viewport) {
  check_viewport(viewport);
  check_indices(mesh);
  const glm::dmat4 vp(view_projection);
  std::vector<std::uint8_t> visible(mesh.positions.size(), 0);
  const double det = glm::determinant(vp);
  if (!std::isfinite(det) || det == 0.0) return visible;  // no camera: nothing is seen
  const glm::dmat4 inverse = glm::inverse(vp);
  DepthBuffer depth(viewport);
  for (std::size_t t = 0; t + 2 < mesh.triangles.size(); t += 3) {
    const glm::dvec4 clip[3] = {to_clip(vp, mesh.positions[mesh.triangles[t]]),
                                to_clip(vp, mesh.positions[mesh.triangles[t + 1]]),
                                to_clip(vp, mesh.positions[mesh.triangles[t + 2]])};
    if (finite(clip[0]) && finite(clip[1]) && finite(clip[2])) depth.draw(clip);
  }

  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const std::optional<glm::dvec3> s = on_screen(vp, mesh.positions[v], viewport);
    if (!s) continue;
    // The tolerance as a world-space step towards the camera along the vertex's own view ray (so the step stays
    // on the same pixel), its depth then compared in NDC like the buffer: this works for any projection, where
    // converting NDC depth back to distance would need the camera's near and far planes.
    const glm::dvec4 near_h = inverse * glm::dvec4(2.0 * s->x / viewport.x - 1.0, 1.0 - 2.0 * s->y / viewport.y,
                                                   -1.0, 1.0);
    const glm::dvec3 near_p = glm::dvec3(near_h) / near_h.w;
    const glm::dvec3 p(mesh.positions[v]);
    const glm::dvec3 pulled = p + (near_p - p) * kRelativeDepthTolerance;
    const glm::dvec4 c = vp * glm::dvec4(pulled, 1.0);
    if (!finite(c) || !(c.w > 0.0)) continue;
    if (c.z / c.w <= depth.farthest_around(s->x, s->y)) visible[v] = 1;
  }
  return visible;
}

VertexSelection::VertexSelection(std::size_t vertex_count) : selected_(vertex_count, 0) {}

void VertexSelection::clear() {
  std::fill(selected_.begin(), selected_.end(), std::uint8_t{0});
  count_ = 0;
}

void VertexSelection::set(std::uint32_t v, bool on) {
  if (v >= selected_.size())
    throw std::out_of_range("VertexSelection::set: vertex " + std::to_string(v) + " of " +
                            std::to_string(selected_.size()));
  const std::uint8_t now = on ? 1 : 0;
  if (selected_[v] == now) return;
  selected_[v] = now;
  count_ = on ? count_ + 1 : count_ - 1;
}

std::vector<std::uint32_t> VertexSelection::ids() const {
  std::vector<std::uint32_t> out;
  out.reserve(count_);
  for (std::size_t v = 0; v < selected_.size(); ++v)
    if (selected_[v]) out.push_back(static_cast<std::uint32_t>(v));
  return out;
}

void select_rect(const EditMesh& mesh, const glm::mat4& view_projection, glm::ivec2 viewport, glm::vec2 corner_a,
                 glm::vec2 corner_b, std::span<const std::uint8_t> visible, SelectOp op, VertexSelection& selection) {
  const glm::dvec2 lo = glm::min(glm::dvec2(corner_a), glm::dvec2(corner_b));
  const glm::dvec2 hi = glm::max(glm::dvec2(corner_a), glm::dvec2(corner_b));
  select_where(mesh, view_projection, viewport, visible, op, selection,
               [&](double x, double y) { return x >= lo.x && x <= hi.x && y >= lo.y && y <= hi.y; });
}

void select_brush(const EditMesh& mesh, const glm::mat4& view_projection, glm::ivec2 viewport, glm::vec2 centre,
                  float radius_px, std::span<const std::uint8_t> visible, SelectOp op, VertexSelection& selection) {
  const double r2 = static_cast<double>(radius_px) * radius_px;
  select_where(mesh, view_projection, viewport, visible, op, selection, [&](double x, double y) {
    const double dx = x - centre.x, dy = y - centre.y;
    return dx * dx + dy * dy <= r2;
  });
}

BindingEditor::BindingEditor(const Mesh& rest_mesh, const Skeleton& skeleton, SkinBinding binding,
                             BindingTables tables)
    : mesh_(rest_mesh),
      skeleton_(skeleton),
      binding_(std::move(binding)),
      tables_(std::move(tables)),
      selection_(rest_mesh.vertex_count()) {
  if (binding_.vertex_count() != mesh_.vertex_count() || binding_.weights.size() != mesh_.vertex_count())
    throw std::invalid_argument("BindingEditor: binding of " + std::to_string(binding_.vertex_count()) +
                                " vertices for mesh '" + mesh_.name + "' of " + std::to_string(mesh_.vertex_count()));
}

bool BindingEditor::bind_selection(int joint, std::string name) {
  if (selection_.count() == 0 || selection_.vertex_count() != mesh_.vertex_count()) return false;
  if (joint < 0 || static_cast<std::size_t>(joint) >= skeleton_.joint_count()) return false;
  if (mesh_.vertex_count() > std::numeric_limits<std::uint32_t>::max()) return false;
  SkinSelection s;
  s.name = name.empty() ? "edit " + std::to_string(edit_count() + 1) : std::move(name);
  s.kind = SkinSelection::Kind::Vertices;
  s.vertices = selection_.ids();
  s.mesh_vertices = static_cast<std::uint32_t>(mesh_.vertex_count());
  s.joints = {skeleton_.joint_names[static_cast<std::size_t>(joint)]};
  s.blend = SkinSelection::Blend::Parent;
  // The file names the joint, and a loaded file finds it by name: a duplicate name would bind another joint.
  if (skeleton_.find_joint(s.joints.front()) != joint) return false;
  // What the editor applies must be what the saved file loads, so the entry goes through the loader itself
  // (which only accepts H-Anim joint names) rather than a copy of its rules.
  try {
    const std::span<const SkinSelection> one(&s, 1);
    if (load_binding_tables("", binding_overrides_json(one)).overrides.size() != 1) return false;
  } catch (const LoadError&) {
    return false;
  }

  Edit edit;
  edit.vertices = s.vertices;
  for (std::uint32_t v : s.vertices) {
    edit.joints.push_back(binding_.joints[v]);
    edit.weights.push_back(binding_.weights[v]);
  }
  apply_selection(s, mesh_, skeleton_, binding_);
  tables_.overrides.push_back(std::move(s));
  undo_.push_back(std::move(edit));
  return true;
}

bool BindingEditor::undo() {
  if (undo_.empty()) return false;
  const Edit& edit = undo_.back();
  for (std::size_t i = 0; i < edit.vertices.size(); ++i) {
    binding_.joints[edit.vertices[i]] = edit.joints[i];
    binding_.weights[edit.vertices[i]] = edit.weights[i];
  }
  undo_.pop_back();
  tables_.overrides.pop_back();
  return true;
}

std::uint32_t weight_heat_rgba(float weight) {
  const double w = std::isnan(weight) ? 0.0 : std::clamp(static_cast<double>(weight), 0.0, 1.0);
  const double x = w * static_cast<double>(kHeatStops.size() - 1);
  const std::size_t k = std::min(static_cast<std::size_t>(x), kHeatStops.size() - 2);
  const double f = x - static_cast<double>(k);
  return pack_rgba(kHeatStops[k] + (kHeatStops[k + 1] - kHeatStops[k]) * f);
}

void BindingEditor::weight_colors(int joint, bool show_selection, std::span<std::uint32_t> rgba) const {
  if (rgba.size() != mesh_.vertex_count())
    throw std::invalid_argument("BindingEditor::weight_colors: " + std::to_string(rgba.size()) + " colours for " +
                                std::to_string(mesh_.vertex_count()) + " vertices");
  for (std::size_t v = 0; v < rgba.size(); ++v) {
    if (show_selection && selection_.contains(static_cast<std::uint32_t>(v))) {
      rgba[v] = kSelectionRgba;
      continue;
    }
    float w = 0.0f;
    for (int k = 0; k < kMaxInfluences; ++k)
      if (binding_.joints[v][k] == joint && binding_.weights[v][k] > 0.0f) w += binding_.weights[v][k];
    rgba[v] = weight_heat_rgba(w);
  }
}

void BindingEditor::save(const std::filesystem::path& path) const {
  write_file_atomically(path, binding_overrides_json(tables_.overrides, tables_.step2_radii));
}

}  // namespace strata
