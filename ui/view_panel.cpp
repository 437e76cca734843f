#include "ui/view_panel.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "components/body.h"
#include "components/skeleton.h"
#include "profiling/profiler.h"
#include "scene/body_settings.h"
#include "scene/crowd.h"
#include "scene/body_settings.h"

namespace strata {

TimingHistory::TimingHistory(std::size_t capacity) : capacity_(std::max<std::size_t>(capacity, 2)) {}

void TimingHistory::push(const Profiler& profiler) {
  for (const SystemStats& s : profiler.stats()) {
    auto it = std::find_if(series_.begin(), series_.end(), [&](const Series& x) { return x.name == s.name; });
    if (it == series_.end()) {
      series_.push_back(Series{s.name, {}, 0.0, 0.0});
      it = series_.end() - 1;
    }
    // A ring would save the erase, but ImGui::PlotLines wants contiguous values and 240 floats move in
    // nanoseconds; the vector keeps the chart code trivial.
    if (it->ms.size() == capacity_) it->ms.erase(it->ms.begin());
    it->ms.push_back(static_cast<float>(s.last_ms));
    it->mean_ms = s.mean_ms;
    it->p95_ms = s.p95_ms;
  }
}

glm::vec2 UiProbe::centre(const std::string& label) const {
  const auto& r = rects.at(label);
  return 0.5f * (r[0] + r[1]);
}

std::vector<DetailLevel> selectable_body_levels(const Crowd& scene) {
  std::vector<DetailLevel> levels;
  const Body* body = scene.rig().body.get();
  if (!body || body->levels.empty()) return levels;
  for (std::size_t l = 0; l < body->levels.size(); ++l) levels.push_back(DetailLevel::mesh(static_cast<int>(l)));
  levels.push_back(DetailLevel::automatic());
  if (crowd_may_use_impostors(scene)) levels.push_back(DetailLevel::impostor());
  if (body->cage)
    for (int d = 1; d <= kMaxSubdivDepth; ++d) levels.push_back(DetailLevel::subdiv(d));
  return levels;
}

namespace {

void note(UiProbe* probe, const std::string& label) {
  if (!probe) return;
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  probe->rects[label] = {glm::vec2(a.x, a.y), glm::vec2(b.x, b.y)};
}

std::string level_label(const Crowd& scene, DetailLevel level) {
  const Body* body = scene.rig().body.get();
  std::string label = level.name();
  if (level.is_mesh() && body && static_cast<std::size_t>(level.index()) < body->levels.size()) {
    label += " (" + std::to_string(body->levels[static_cast<std::size_t>(level.index())].mesh.vertex_count()) + " v)";
  } else if (level.is_automatic()) {
    label += crowd_may_use_impostors(scene) ? " (by size on screen, impostors far)" : " (by size on screen)";
  } else if (level.is_impostor()) {
    label += " (every walker a quad)";
  } else if (level.is_subdiv()) {
    label += " (cage refined " + std::to_string(level.index()) + "x)";
  }
  return label;
}

const char* skinning_mode_label(SkinningMode mode) {
  switch (mode) {
    case SkinningMode::DualQuaternion: return "dqs (dual quaternions)";
    case SkinningMode::CentresOfRotation: return "cor (centres of rotation)";
    default: return "lbs (linear blend)";
  }
}

void playback_section(ViewPanelState& s, UiProbe* probe) {
  if (ImGui::Button(s.paused ? "Resume" : "Pause", ImVec2(80, 0))) s.paused = !s.paused;
  note(probe, "Pause");
  ImGui::SameLine();
  ImGui::BeginDisabled(!s.paused);
  if (ImGui::Button("Step", ImVec2(60, 0))) ++s.step_requests;
  note(probe, "Step");
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("Screenshot")) s.screenshot_requested = true;
  note(probe, "Screenshot");
  ImGui::SliderFloat("time scale", &s.time_scale, 0.0f, 3.0f, "%.2fx");
  note(probe, "time scale");
  if (ImGui::Button("Frame crowd")) s.frame_camera_requested = true;
  note(probe, "Frame crowd");
  ImGui::SameLine();
  ImGui::Checkbox("skeletons", &s.show_skeleton);
  note(probe, "skeletons");
  ImGui::SameLine();
  ImGui::Checkbox("high quality", &s.high_quality);
  note(probe, "high quality");
}

void crowd_section(Crowd& scene, ViewPanelState& s, UiProbe* probe) {
  ImGui::Text("%zu walkers, %zu triangles drawn", scene.walker_count(), s.triangles_drawn);
  ImGui::InputInt("walkers", &s.walkers, 1, 25);
  note(probe, "walkers");
  s.walkers = std::clamp(s.walkers, 1, 100000);
  ImGui::InputInt("seed", &s.seed);
  note(probe, "seed");
  s.seed = std::max(s.seed, 0);
  if (ImGui::Button("New crowd")) s.rebuild_requested = true;
  note(probe, "New crowd");
}

void level_section(Crowd& scene, UiProbe* probe) {
  const std::vector<DetailLevel> levels = selectable_body_levels(scene);
  if (levels.empty()) {
    ImGui::TextDisabled("no body (skeletons only)");
    return;
  }
  const DetailLevel current = scene.skin.level;
  if (ImGui::BeginCombo("level", level_label(scene, current).c_str())) {
    for (DetailLevel level : levels) {
      const bool selected = level == current;
      if (ImGui::Selectable(level_label(scene, level).c_str(), selected) && !selected) set_detail_level(scene, level);
      note(probe, "level:" + level.name());
      if (selected) ImGui::SetItemDefaultFocus();
    }
    ImGui::EndCombo();
  }
  note(probe, "level");
  // Skinning mode: every level at once. The first switch to centres of rotation may pause for the body's
  // precomputation (then cached on disk).
  const SkinningMode mode = scene.skin.mode;
  if (ImGui::BeginCombo("skinning", skinning_mode_label(mode))) {
    for (const SkinningMode m : kSkinningModes) {
      const bool selected = m == mode;
      if (ImGui::Selectable(skinning_mode_label(m), selected) && !selected) set_skinning_mode(scene, m);
      note(probe, std::string("skinning:") + skinning_mode_name(m));
      if (selected) ImGui::SetItemDefaultFocus();
    }
    ImGui::EndCombo();
  }
  note(probe, "skinning");
  LodPolicy& policy = scene.lod.policy;
  ImGui::BeginDisabled(current != DetailLevel::automatic());
  ImGui::SliderFloat("level 0 above", &policy.level0_px, 50.0f, 1000.0f, "%.0f px");
  note(probe, "level 0 above");
  ImGui::SliderFloat("level 1 above", &policy.level1_px, 20.0f, 600.0f, "%.0f px");
  note(probe, "level 1 above");
  ImGui::SliderFloat("hysteresis", &policy.hysteresis, 1.0f, 2.0f, "%.2f");
  note(probe, "hysteresis");
  policy.level1_px = std::min(policy.level1_px, policy.level0_px);
  if (crowd_may_use_impostors(scene)) {
    ImGui::SliderFloat("impostor below", &policy.impostor_px, 0.0f, 400.0f, "%.0f px");
    note(probe, "impostor below");
    int budget = static_cast<int>(std::min<std::uint32_t>(policy.mesh_budget, 100000));
    if (ImGui::SliderInt("mesh budget", &budget, 0, 500, budget == 0 ? "no cap" : "%d walkers"))
      policy.mesh_budget = static_cast<std::uint32_t>(std::max(budget, 0));
    note(probe, "mesh budget");
    policy.impostor_px = std::min(policy.impostor_px, policy.level1_px);
  }
  ImGui::EndDisabled();
  const auto counts = scene.lod.counts;
  ImGui::Text("meshes at 0/1/2: %zu / %zu / %zu", counts[0], counts[1], counts[2]);
  ImGui::Text("impostors %zu, culled %zu", scene.lod.impostors, counts[3]);
  if (scene.lod.over_budget > 0) ImGui::Text("over the mesh budget: %zu (drawn as impostors)", scene.lod.over_budget);
}

void gait_section(Crowd& scene, UiProbe* probe) {
  if (scene.motion.source != MotionSource::Walk) {
    ImGui::TextDisabled("the walkers play clips; gait applies to the walk generator");
    return;
  }
  GaitStyle& g = scene.motion.style;
  // Ranges: about twice each default either way, within what the IK limits can still follow.
  ImGui::SliderFloat("pelvis yaw", &g.pelvis_yaw, 0.0f, 0.2f, "%.3f rad");
  note(probe, "pelvis yaw");
  ImGui::SliderFloat("pelvis list", &g.pelvis_tilt, 0.0f, 0.2f, "%.3f rad");
  ImGui::SliderFloat("list lag", &g.pelvis_list_lag, 0.0f, 0.5f, "%.2f cycle");
  ImGui::SliderFloat("lateral sway", &g.lateral_sway, 0.0f, 0.06f, "%.3f m");
  ImGui::SliderFloat("anterior tilt", &g.pelvis_anterior_tilt, -0.2f, 0.3f, "%.3f rad");
  ImGui::SliderFloat("pelvis rise", &g.pelvis_rise_max, -0.03f, 0.03f, "%.3f m");
  ImGui::SliderFloat("footprint lead", &g.footprint_lead, 0.3f, 0.9f, "%.2f steps");
  ImGui::SliderFloat("lead drop, long step", &g.lead_long_step_drop, 0.0f, 0.5f, "%.2f");
  ImGui::SliderFloat("lead rise, short step", &g.lead_short_step_rise, 0.0f, 0.8f, "%.2f");
  ImGui::SliderFloat("heel off", &g.heel_off, 0.1f, 0.9f, "%.2f of stance");
  ImGui::SliderFloat("heel hold from", &g.heel_hold_from, 0.2f, 1.0f, "%.2f of stance");  // 1: the schedule alone
  ImGui::SliderFloat("toe-off pitch", &g.toe_off_pitch, 0.0f, 1.3f, "%.2f rad");
  ImGui::SliderFloat("swing clearance", &g.swing_clearance, 0.0f, 0.15f, "%.3f m");
  ImGui::SliderFloat("swing catch-up", &g.swing_catch_up, 0.0f, 0.9f, "%.2f of swing");  // 0: spread evenly
  ImGui::SliderFloat("swing lands from", &g.swing_land_from, 0.1f, 0.95f, "%.2f of swing");
  // The fast walk: per reference step a step runs beyond 1.05 of it (0 at 1.2 m/s, up to 0.24 at 1.8 m/s).
  ImGui::SliderFloat("fast: more pelvis yaw", &g.yaw_long_step_rise, 0.0f, 1.2f, "%.2f");
  ImGui::SliderFloat("fast: more pelvis list", &g.tilt_long_step_rise, 0.0f, 0.5f, "%.2f");
  ImGui::SliderFloat("fast: more toe-off pitch", &g.toe_off_long_step_rise, 0.0f, 2.5f, "%.2f");
  ImGui::SliderFloat("fast: lower swing", &g.lift_long_step_drop, 0.0f, 1.6f, "%.2f");
  ImGui::SliderFloat("fast: softer bob", &g.bob_long_step_drop, 0.0f, 3.5f, "%.2f");
  ImGui::SliderFloat("arm swing", &g.arm_swing, 0.0f, 0.4f, "%.3f m");
  note(probe, "arm swing");
  if (ImGui::Button("Default gait")) g = GaitStyle{};
  note(probe, "Default gait");
}

void muscle_section(Crowd& scene, UiProbe* probe) {
  if (!scene.has_muscles()) {
    ImGui::TextDisabled("this rig has no muscle layer");
    return;
  }
  bool on = scene.muscles_enabled();
  if (ImGui::Checkbox("muscles on", &on)) set_muscles_enabled(scene, on);
  note(probe, "muscles on");
  const MuscleSet& set = scene.rig().muscles->set;
  MuscleGains gains = scene.skin.gains;
  bool changed = false;
  changed |= ImGui::SliderFloat("all muscles", &gains.global, 0.0f, 5.0f, "%.2fx");
  note(probe, "all muscles");
  if (gains.line.size() != set.lines.size()) gains.line.resize(set.lines.size(), 1.0f);
  for (std::size_t m = 0; m < set.lines.size(); ++m)
    changed |= ImGui::SliderFloat(set.lines[m].name.c_str(), &gains.line[m], 0.0f, 5.0f, "%.2fx");
  if (ImGui::Button("Reset gains")) {
    gains = MuscleGains{};
    changed = true;
  }
  note(probe, "Reset gains");
  // Only a change goes to the scene: set_muscle_gains re-derives the per-vertex coefficients.
  if (changed) set_muscle_gains(scene, std::move(gains));
}

void timing_section(const ViewPanelState& s) {
  ImGui::Text("%.1f fps", static_cast<double>(s.fps));
  for (const TimingHistory::Series& series : s.timings.series()) {
    if (series.ms.empty()) continue;
    const float peak = *std::max_element(series.ms.begin(), series.ms.end());
    char overlay[96];
    std::snprintf(overlay, sizeof overlay, "%s  %.2f ms (mean %.2f, p95 %.2f)", series.name.c_str(),
                  static_cast<double>(series.ms.back()), series.mean_ms, series.p95_ms);
    ImGui::PushID(series.name.c_str());
    // Each system on its own scale: a 0.2 ms system would be a flat line on the frame's 20 ms axis.
    ImGui::PlotLines("", series.ms.data(), static_cast<int>(series.ms.size()), 0, overlay, 0.0f,
                     std::max(peak * 1.1f, 0.01f), ImVec2(320.0f, 36.0f));
    ImGui::PopID();
  }
}

void binding_section(Crowd& scene, BindingEditState& b, UiProbe* probe) {
  if (!scene.rig().body || scene.rig().body->levels.empty()) {
    ImGui::TextDisabled("no body to bind");
    return;
  }
  if (!b.active) {
    ImGui::TextWrapped("Pick skin vertices with the mouse and bind them to a joint and its parent (the paper's "
                       "manual step, saved as a binding overrides file).");
    if (ImGui::Button("Edit binding")) b.activate_requested = true;
    note(probe, "Edit binding");
    ImGui::Checkbox("rest pose", &b.rest_pose);
    note(probe, "rest pose");
    return;
  }
  ImGui::Text("level %d: %zu selected, %zu edits", b.level, b.selected, b.edits);
  int tool = static_cast<int>(b.tool);
  ImGui::RadioButton("click", &tool, 0);
  note(probe, "tool:click");
  ImGui::SameLine();
  ImGui::RadioButton("box", &tool, 1);
  note(probe, "tool:box");
  ImGui::SameLine();
  ImGui::RadioButton("brush", &tool, 2);
  note(probe, "tool:brush");
  b.tool = static_cast<BindingEditState::Tool>(tool);
  ImGui::BeginDisabled(b.tool != BindingEditState::Tool::Brush);
  ImGui::SliderFloat("brush radius", &b.brush_radius_px, 2.0f, 120.0f, "%.0f px");
  ImGui::EndDisabled();
  ImGui::Checkbox("select through", &b.select_through);
  ImGui::SameLine();
  ImGui::Checkbox("rest pose", &b.rest_pose);
  note(probe, "rest pose");
  const Skeleton& skeleton = scene.rig().skeleton;
  const char* current = b.joint >= 0 && static_cast<std::size_t>(b.joint) < skeleton.joint_count()
                            ? skeleton.joint_names[static_cast<std::size_t>(b.joint)].c_str()
                            : "(joint)";
  if (ImGui::BeginCombo("joint", current, ImGuiComboFlags_HeightLargest)) {
    for (std::size_t j = 0; j < skeleton.joint_count(); ++j) {
      const bool selected = static_cast<int>(j) == b.joint;
      if (ImGui::Selectable(skeleton.joint_names[j].c_str(), selected)) b.joint = static_cast<int>(j);
      note(probe, "joint:" + skeleton.joint_names[j]);
      if (selected) ImGui::SetItemDefaultFocus();
    }
    ImGui::EndCombo();
  }
  note(probe, "joint");
  const int parent = b.joint >= 0 ? skeleton.parents[static_cast<std::size_t>(b.joint)] : -1;
  ImGui::TextDisabled("blends with its parent: %s",
                      parent >= 0 ? skeleton.joint_names[static_cast<std::size_t>(parent)].c_str() : "(none: rigid)");
  ImGui::Checkbox("show weights", &b.show_weights);
  if (ImGui::Button("Bind selection")) b.bind_requested = true;
  note(probe, "Bind selection");
  ImGui::SameLine();
  if (ImGui::Button("Undo")) b.undo_requested = true;
  note(probe, "Undo");
  ImGui::SameLine();
  if (ImGui::Button("Clear")) b.clear_requested = true;
  note(probe, "Clear");
  ImGui::InputText("file", &b.save_path);
  note(probe, "file");
  if (ImGui::Button("Save overrides")) b.save_requested = true;
  note(probe, "Save overrides");
  ImGui::SameLine();
  if (ImGui::Button("Done")) b.deactivate_requested = true;
  note(probe, "Done");
  ImGui::TextDisabled("left: select (Shift adds, Ctrl removes), Alt+left: orbit");
  // The drag's outline over the scene.
  ImDrawList* overlay = ImGui::GetForegroundDrawList();
  const glm::vec2 from = b.drag_from / b.pixels_per_unit, at = b.cursor / b.pixels_per_unit;
  if (b.dragging && b.tool == BindingEditState::Tool::Box)
    overlay->AddRect(ImVec2(from.x, from.y), ImVec2(at.x, at.y), IM_COL32(255, 255, 255, 220));
  if (b.tool == BindingEditState::Tool::Brush && !ImGui::GetIO().WantCaptureMouse)
    overlay->AddCircle(ImVec2(at.x, at.y), b.brush_radius_px / b.pixels_per_unit.x, IM_COL32(255, 255, 255, 160), 32);
}

}  // namespace

void draw_view_panel(Crowd& scene, ViewPanelState& state, UiProbe* probe) {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  // Auto-resized to the open tab: every tab fits a 720p window, so nothing needs scrolling, and a tab is one
  // concern (a long page of collapsing headers outgrew the screen once the muscle sliders were open).
  ImGui::Begin("Strata", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  ImGui::PushItemWidth(180.0f);
  playback_section(state, probe);
  if (ImGui::BeginTabBar("sections")) {
    const std::string select = std::move(state.select_tab);
    state.select_tab.clear();
    const auto tab = [&](const char* name, auto&& body) {
      const bool open =
          ImGui::BeginTabItem(name, nullptr, select == name ? ImGuiTabItemFlags_SetSelected : ImGuiTabItemFlags_None);
      note(probe, std::string("tab:") + name);
      if (open) {
        body();
        ImGui::EndTabItem();
      }
    };
    tab("Crowd", [&] {
      crowd_section(scene, state, probe);
      ImGui::Separator();
      level_section(scene, probe);
    });
    tab("Gait", [&] { gait_section(scene, probe); });
    tab("Muscles", [&] { muscle_section(scene, probe); });
    tab("Timings", [&] { timing_section(state); });
    tab("Binding", [&] { binding_section(scene, state.binding, probe); });
    ImGui::EndTabBar();
  }
  if (!state.last_message.empty()) ImGui::TextWrapped("%s", state.last_message.c_str());
  ImGui::PopItemWidth();
  ImGui::End();
}

}  // namespace strata
