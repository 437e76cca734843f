#pragma once
// The state of one `strata view` session apart from its window: the scene, the panel's state, and what the
// panel's requests do (a new crowd that keeps the user's settings, pause / single-step / time scale). Kept out of
// cmd_view.cpp so the tests can drive it without a display.
#include <memory>
#include <vector>

#include <glm/mat4x4.hpp>

#include "scene/scene_setup.h"
#include "render/scene_draw.h"
#include "rig/binding.h"
#include "ui/view_panel.h"

namespace strata {
class Profiler;
class BindingEditor;
}

namespace strata {

// The mouse as the binding editor reads it: framebuffer pixels, y down.
struct EditorMouse {
  glm::vec2 cursor{0.0f};
  bool pressed = false, released = false, down = false;
  bool shift = false, ctrl = false;
};

class ViewSession {
 public:
  // Builds the scene (LoadError / std::invalid_argument as build_scene).
  explicit ViewSession(SceneOptions options);
  ~ViewSession();
  ViewSession(const ViewSession&) = delete;
  ViewSession& operator=(const ViewSession&) = delete;

  Crowd& scene() { return *scene_; }
  const Crowd& scene() const { return *scene_; }
  ViewPanelState& panel() { return panel_; }
  const SceneOptions& options() const { return options_; }

  // Handles the panel's request for a new crowd: rebuilt with the panel's walker count and seed, keeping the body
  // level, level-of-detail policy, gait style, muscle switch and gains. True when the scene was replaced (the
  // caller reframes the camera; references into the old scene are gone). When the new crowd cannot be built the
  // old one stays and panel().last_message says why.
  bool apply_crowd_request();

  // Advances the simulation for `real_dt` seconds of wall time: scaled by the panel's time scale while running;
  // while paused, one 1/30 s step per pending step request (and a 0 s frame when the scene is new, so a paused
  // new crowd still has bodies to draw). Returns the simulated seconds.
  float advance(float real_dt, Profiler& profiler);

  // ---- The binding editor (the paper's manual step 3; panel state in panel().binding) ----
  // Acts on the Binding tab's requests: start/stop editing (a mesh level is forced; the crowd pauses), bind the
  // selection to the chosen joint and its parent, undo, clear, save the overrides file, rest pose on/off.
  // Edits take effect on the crowd at once (Crowd::set_body) and survive a new crowd.
  void apply_binding_requests();
  // While editing: the current tool on the walker under the cursor when the button went down. Click picks one
  // vertex (Shift adds, Ctrl removes); Box selects what the rectangle covers on release; Brush paints while held.
  // Box and brush take visible vertices only unless "select through" is on.
  void binding_mouse(const EditorMouse& mouse, const glm::mat4& view_projection, glm::ivec2 viewport);
  // While editing, gives the draws per-vertex colours: the chosen joint's weight as heat, the selection white.
  void colour_draws(std::vector<BodyDrawInput>& draws);
  const BindingEditor* binding_editor() const { return editor_.get(); }
  // The overrides so far: the shipped (or --binding-overrides) entries and every edit, in order.
  const BindingTables& binding_tables() const;

 private:
  void start_editing();
  void stop_editing();
  void publish_edit(const char* what);
  // Mesh-order positions of block `block` of the current draw (the skin output is in layout order).
  void block_positions(std::size_t block, std::vector<glm::vec3>& out) const;
  std::size_t block_count() const;


  SceneOptions options_;
  std::unique_ptr<Crowd> scene_;
  ViewPanelState panel_;
  bool fresh_ = true;  // no simulate() since the scene was built

  std::unique_ptr<BindingEditor> editor_;
  BindingTables tables_;                     // valid once editing started
  bool have_tables_ = false;
  std::shared_ptr<const Body> edited_body_;  // null until the first edit; re-applied to a new crowd
  std::vector<std::uint32_t> colours_;
  // The drag in progress.
  long press_block_ = -1;
  std::vector<glm::vec3> press_positions_;
  std::vector<std::uint8_t> press_visible_;
};

}  // namespace strata
