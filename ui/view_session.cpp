#include "ui/view_session.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "components/body.h"
#include "profiling/profiler.h"
#include "rig/binding_editor.h"
#include "rig/body_rig.h"
#include "scene/body_settings.h"
#include "scene/step.h"

namespace strata {

ViewSession::ViewSession(SceneOptions options) : options_(std::move(options)), scene_(build_scene(options_)) {
  if (!options_.binding_overrides.empty()) panel_.binding.save_path = options_.binding_overrides;
  panel_.binding.rest_pose = options_.rest;  // else the first frame would "toggle" --rest off
  panel_.walkers = static_cast<int>(std::min<std::size_t>(options_.walkers, 100000));
  panel_.seed = static_cast<int>(options_.seed);
}

ViewSession::~ViewSession() = default;

bool ViewSession::apply_crowd_request() {
  const bool pose_change = panel_.binding.rest_pose != options_.rest;
  if (!panel_.rebuild_requested && !pose_change) return false;
  panel_.rebuild_requested = false;
  const bool was_editing = editor_ != nullptr;
  if (was_editing) stop_editing();
  SceneOptions next = options_;
  next.rest = panel_.binding.rest_pose;
  next.walkers = static_cast<std::size_t>(std::max(panel_.walkers, 1));
  next.seed = static_cast<std::uint64_t>(std::max(panel_.seed, 0));
  next.level = scene_->skin.level;
  std::unique_ptr<Crowd> built;
  try {
    built = build_scene(next);
  } catch (const std::exception& e) {
    // The viewer keeps the crowd it has rather than closing over a request it cannot meet.
    panel_.binding.rest_pose = options_.rest;
    panel_.last_message = std::string("no new crowd: ") + e.what();
    if (was_editing) start_editing();
    return false;
  }
  // What the user tuned at run time survives a new crowd; the crowd itself (count, seed) is what changes.
  built->lod.policy = scene_->lod.policy;
  built->motion.style = scene_->motion.style;
  set_skinning_mode(*built, scene_->skin.mode);
  if (built->has_muscles()) {
    set_muscles_enabled(*built, scene_->muscles_enabled());
    set_muscle_gains(*built, scene_->skin.gains);
  }
  if (edited_body_) set_body(*built, edited_body_);  // the edits belong to the body, not to the crowd
  scene_ = std::move(built);
  fresh_ = true;
  if (was_editing) start_editing();
  options_ = std::move(next);
  panel_.last_message = "new crowd: " + std::to_string(scene_->walker_count()) + " walkers, seed " +
                        std::to_string(options_.seed);
  return true;
}

float ViewSession::advance(float real_dt, Profiler& profiler) {
  if (!panel_.paused) {
    const float dt = std::max(real_dt, 0.0f) * std::clamp(panel_.time_scale, 0.0f, 10.0f);
    step(*scene_, dt, profiler);
    fresh_ = false;
    return dt;
  }
  const int steps = std::max(panel_.step_requests, 0);
  panel_.step_requests = 0;
  constexpr float kStep = 1.0f / 30.0f;
  if (steps == 0 && fresh_) step(*scene_, 0.0f, profiler);
  fresh_ = false;
  for (int s = 0; s < steps; ++s) step(*scene_, kStep, profiler);
  return static_cast<float>(steps) * kStep;
}

namespace {

// The body with one level's weights replaced (meshes and cage copied; its subdivision cache starts empty).
std::shared_ptr<const Body> with_level_binding(const Body& body, int level, const SkinBinding& binding) {
  auto edited = std::make_shared<Body>(body);
  edited->levels[static_cast<std::size_t>(level)].binding = binding;
  return edited;
}

// Slab test; a ray starting inside the box hits it.
bool ray_hits_box(const PickRay& ray, const glm::vec3& lo, const glm::vec3& hi) {
  float t0 = 0.0f, t1 = std::numeric_limits<float>::max();
  for (int a = 0; a < 3; ++a) {
    const float d = ray.direction[a];
    if (std::abs(d) < 1e-12f) {
      if (ray.origin[a] < lo[a] || ray.origin[a] > hi[a]) return false;
      continue;
    }
    float ta = (lo[a] - ray.origin[a]) / d, tb = (hi[a] - ray.origin[a]) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

bool is_mesh_level(const Crowd& scene, DetailLevel level) {
  const Body* body = scene.rig().body.get();
  return body && level.is_mesh() && static_cast<std::size_t>(level.index()) < body->levels.size();
}

}  // namespace

const BindingTables& ViewSession::binding_tables() const {
  if (editor_) return editor_->tables();
  return have_tables_ ? tables_ : shipped_binding_tables(options_.body);
}

void ViewSession::start_editing() {
  Crowd& scene = *scene_;
  BindingEditState& b = panel_.binding;
  if (!scene.rig().body || scene.rig().body->levels.empty()) {
    b.active = false;
    panel_.last_message = "binding editor: this scene has no body";
    return;
  }
  if (!is_mesh_level(scene, scene.skin.level)) {
    set_detail_level(scene, DetailLevel::mesh(0));  // weights belong to one mesh; auto and S levels mix or refine meshes
    fresh_ = true;
  }
  if (!have_tables_) {
    // The tables the scene's body was bound with: the shipped ones, or --binding-overrides's file, which is then
    // also where Save writes unless the user names another.
    tables_ = options_.binding_overrides.empty()
                  ? shipped_binding_tables(options_.body)
                  : load_binding_overrides_file(options_.binding_overrides, shipped_binding_tables(options_.body));
    have_tables_ = true;
  }
  const int level = scene.skin.level.index();
  const BodyLevel& body_level = scene.rig().body->levels[static_cast<std::size_t>(level)];
  editor_ = std::make_unique<BindingEditor>(body_level.mesh, scene.rig().skeleton, body_level.binding, tables_);
  b.active = true;
  b.level = level;
  if (b.joint < 0 || static_cast<std::size_t>(b.joint) >= scene.rig().skeleton.joint_count()) {
    const int sacroiliac = scene.rig().skeleton.find_joint("sacroiliac");
    b.joint = sacroiliac >= 0 ? sacroiliac : 0;
  }
  b.selected = 0;
  b.edits = 0;
  panel_.paused = true;  // a still pose to pick on; Resume shows the edit in motion
}

void ViewSession::stop_editing() {
  if (editor_) {
    tables_ = editor_->tables();
    editor_.reset();
  }
  panel_.binding.active = false;
  panel_.binding.dragging = false;
  press_block_ = -1;
}

void ViewSession::publish_edit(const char* what) {
  const int level = panel_.binding.level;
  edited_body_ = with_level_binding(*scene_->rig().body, level, editor_->binding());
  set_body(*scene_, edited_body_);
  fresh_ = true;
  panel_.last_message = std::string(what) + ": level " + std::to_string(level) + ", " +
                        std::to_string(editor_->edit_count()) + " edits this level";
}

void ViewSession::apply_binding_requests() {
  BindingEditState& b = panel_.binding;
  if (b.activate_requested && !editor_) start_editing();
  if (b.deactivate_requested && editor_) stop_editing();
  b.activate_requested = b.deactivate_requested = false;
  if (editor_ && scene_->skin.level != DetailLevel::mesh(b.level)) {
    // The user picked another level: keep what was done and edit that level's mesh, or stop at auto/S levels.
    stop_editing();
    if (is_mesh_level(*scene_, scene_->skin.level)) start_editing();
    else panel_.last_message = "binding editor stopped: pick level 0, 1 or 2 to edit weights";
  }
  if (!editor_) {
    b.bind_requested = b.undo_requested = b.clear_requested = b.save_requested = false;
    return;
  }
  if (b.clear_requested) editor_->selection().clear();
  if (b.bind_requested) {
    const std::size_t n = editor_->selection().count();
    if (editor_->bind_selection(b.joint)) {
      editor_->selection().clear();
      publish_edit(("bound " + std::to_string(n) + " vertices to " + scene_->rig().skeleton.joint_names[static_cast<std::size_t>(b.joint)]).c_str());
    } else {
      panel_.last_message = "nothing to bind: select vertices first";
    }
  }
  if (b.undo_requested) {
    if (editor_->undo()) publish_edit("undone");
    else panel_.last_message = "nothing to undo";
  }
  if (b.save_requested) {
    try {
      editor_->save(b.save_path);
      panel_.last_message = "saved " + std::to_string(editor_->tables().overrides.size()) + " overrides to " +
                            b.save_path + " (use it with --binding-overrides)";
    } catch (const std::exception& e) {
      panel_.last_message = std::string("save failed: ") + e.what();
    }
  }
  b.bind_requested = b.undo_requested = b.clear_requested = b.save_requested = false;
  b.selected = editor_->selection().count();
  b.edits = editor_->edit_count();
}

std::size_t ViewSession::block_count() const { return current_skinned(*scene_).vertex_count ? current_skinned(*scene_).walkers : 0; }

void ViewSession::block_positions(std::size_t block, std::vector<glm::vec3>& out) const {
  const SkinnedCrowd& s = current_skinned(*scene_);
  const std::vector<std::uint32_t>& original = current_layout(*scene_).original;
  out.resize(original.size());
  for (std::size_t i = 0; i < original.size(); ++i) out[original[i]] = s.position(block, i);
}

void ViewSession::binding_mouse(const EditorMouse& m, const glm::mat4& view_projection, glm::ivec2 viewport) {
  BindingEditState& b = panel_.binding;
  b.cursor = m.cursor;
  // A minimised window has an empty framebuffer: nothing to pick on (and pick_ray would refuse it).
  if (viewport.x <= 0 || viewport.y <= 0) return;
  if (!editor_ || block_count() == 0 || current_layout(*scene_).original.empty()) return;
  const Mesh& mesh = scene_->rig().body->levels[static_cast<std::size_t>(b.level)].mesh;
  const SelectOp op = m.shift ? SelectOp::Add : m.ctrl ? SelectOp::Subtract : SelectOp::Replace;
  VertexSelection& selection = editor_->selection();
  if (m.pressed) {
    // The walker under the cursor: the nearest hit over every drawn walker; on a miss, the walker whose centre
    // projects nearest to the cursor (a box may well start beside the body).
    const PickRay ray = pick_ray(view_projection, m.cursor, viewport);
    std::vector<glm::vec3> positions;
    float best = std::numeric_limits<float>::max(), best_screen = best;
    long hit_block = -1, near_block = -1;
    std::optional<std::uint32_t> hit_vertex;
    const SkinnedCrowd& skinned = current_skinned(*scene_);
    for (std::size_t k = 0; k < block_count(); ++k) {
      // The block's bounds straight from the SoA output: cheap, and a ray that misses them skips the block's
      // triangles (a click over a crowd of 1,000 would otherwise test every triangle of every walker).
      const std::size_t first = k * skinned.stride, n = skinned.vertex_count;
      glm::vec3 lo{skinned.px[first], skinned.py[first], skinned.pz[first]}, hi = lo;
      for (std::size_t i = first; i < first + n; ++i) {
        const glm::vec3 p{skinned.px[i], skinned.py[i], skinned.pz[i]};
        lo = glm::min(lo, p), hi = glm::max(hi, p);
      }
      const glm::vec4 c = view_projection * glm::vec4(0.5f * (lo + hi), 1.0f);
      if (c.w > 0.0f) {
        const glm::vec2 px{(c.x / c.w * 0.5f + 0.5f) * static_cast<float>(viewport.x),
                           (0.5f - c.y / c.w * 0.5f) * static_cast<float>(viewport.y)};
        const float screen = glm::length(px - m.cursor);
        if (screen < best_screen) best_screen = screen, near_block = static_cast<long>(k);
      }
      if (!ray_hits_box(ray, lo, hi)) continue;
      block_positions(k, positions);
      if (const auto v = pick_vertex(EditMesh{positions, mesh.triangles}, ray)) {
        const float d = glm::length(positions[*v] - ray.origin);
        if (d < best) best = d, hit_block = static_cast<long>(k), hit_vertex = v;
      }
    }
    press_block_ = hit_block >= 0 ? hit_block : near_block;
    if (b.tool == BindingEditState::Tool::Click) {
      if (op == SelectOp::Replace) selection.clear();
      if (hit_vertex) selection.set(*hit_vertex, op != SelectOp::Subtract);
      press_block_ = -1;
    } else if (press_block_ >= 0) {
      block_positions(static_cast<std::size_t>(press_block_), press_positions_);
      press_visible_.clear();
      if (!b.select_through)
        press_visible_ = visible_vertices(EditMesh{press_positions_, mesh.triangles}, view_projection, viewport);
      b.dragging = true;
      b.drag_from = m.cursor;
      if (b.tool == BindingEditState::Tool::Brush && op == SelectOp::Replace) selection.clear();
    }
  }
  const EditMesh edit{press_positions_, mesh.triangles};
  if (b.dragging && b.tool == BindingEditState::Tool::Brush && (m.down || m.released))
    select_brush(edit, view_projection, viewport, m.cursor, b.brush_radius_px, press_visible_,
                 m.ctrl ? SelectOp::Subtract : SelectOp::Add, selection);
  if (b.dragging && m.released) {
    if (b.tool == BindingEditState::Tool::Box)
      select_rect(edit, view_projection, viewport, b.drag_from, m.cursor, press_visible_, op, selection);
    b.dragging = false;
    press_block_ = -1;
  }
  b.selected = selection.count();
}

void ViewSession::colour_draws(std::vector<BodyDrawInput>& draws) {
  if (!editor_ || draws.size() != 1 || current_layout(*scene_).original.empty()) return;
  const BindingEditState& b = panel_.binding;
  const std::vector<std::uint32_t>& original = current_layout(*scene_).original;
  std::vector<std::uint32_t> mesh_colours(editor_->binding().vertex_count());
  editor_->weight_colors(b.joint, true, mesh_colours);
  if (!b.show_weights)  // selection only: everything else plain skin
    for (std::size_t v = 0; v < mesh_colours.size(); ++v)
      if (!editor_->selection().contains(static_cast<std::uint32_t>(v))) mesh_colours[v] = 0;
  BodyDrawInput& d = draws[0];
  colours_.assign(d.walker_count * d.stride, 0u);
  for (std::size_t k = 0; k < d.walker_count; ++k)
    for (std::size_t i = 0; i < original.size() && i < d.vertex_count; ++i)
      colours_[k * d.stride + i] = mesh_colours[original[i]];
  d.rgba = colours_.data();
}

}  // namespace strata
