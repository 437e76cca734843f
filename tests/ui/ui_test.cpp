// The viewer's control panel, driven headless: a real ImGui context drawn by its OpenGL 3 backend into an FBO of
// a Mesa EGL context, clicked with a scripted mouse at the rectangles the panel reports (UiProbe), acting on a
// real crowd scene through ViewSession. No window and no display needed.
#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <memory>
#include <vector>

#include "ui/view_session.h"
#include "components/body.h"
#include "profiling/profiler.h"
#include "render/camera.h"
#include "render/gl_context.h"
#include "rig/binding.h"
#include "rig/binding_editor.h"
#include "tests/apps/strata_cli_runner.h"
#include "tests/temp_dir.h"
#include "ui/imgui_layer.h"
#include "ui/view_panel.h"
#include "scene/state_hash.h"
#include "scene/body_settings.h"
#include "scene/step.h"

namespace strata {
namespace {

constexpr int kWidth = 900;
constexpr int kHeight = 1000;

class UiTest : public ::testing::Test {
 protected:
  void SetUp() override {
    try {
      context_ = create_headless_gl_context();
    } catch (const std::exception& e) {
      FAIL() << "headless GL context unavailable (CI has Mesa, so this is a failure): " << e.what();
    }
    SceneOptions options;
    options.walkers = 4;
    options.threads = 1;
    session_ = std::make_unique<ViewSession>(options);
    glCreateTextures(GL_TEXTURE_2D, 1, &texture_);
    glTextureStorage2D(texture_, 1, GL_RGBA8, kWidth, kHeight);
    glCreateFramebuffers(1, &fbo_);
    glNamedFramebufferTexture(fbo_, GL_COLOR_ATTACHMENT0, texture_, 0);
    ASSERT_EQ(glCheckNamedFramebufferStatus(fbo_, GL_FRAMEBUFFER), static_cast<GLenum>(GL_FRAMEBUFFER_COMPLETE));
    ui_ = std::make_unique<ImGuiLayer>();
  }

  void TearDown() override {
    ui_.reset();
    if (fbo_) glDeleteFramebuffers(1, &fbo_);
    if (texture_) glDeleteTextures(1, &texture_);
    context_.reset();
  }

  // One UI frame over a black framebuffer with the mouse at `mouse` (negative: away), button as given.
  void frame(glm::vec2 mouse = {-1.0f, -1.0f}, bool down = false) {
    const float black[4] = {0.0f, 0.0f, 0.0f, 1.0f};
    glClearNamedFramebufferfv(fbo_, GL_COLOR, 0, black);
    UiFrameInput in;
    in.display_size = {static_cast<float>(kWidth), static_cast<float>(kHeight)};
    in.mouse = mouse;
    in.left_down = down;
    ui_->begin_frame(in);
    draw_view_panel(session_->scene(), session_->panel(), &probe_);
    ui_->render({kWidth, kHeight}, fbo_);
  }

  // Hover, press, release on a widget the panel drew last frame (ImGui buttons fire on release).
  void click(const std::string& label) {
    const glm::vec2 at = probe_.centre(label);
    frame(at, false);
    frame(at, true);
    frame(at, false);
  }

  // Press at the left end of a slider: ImGui sets a slider to the value under the mouse, here its minimum.
  void press_slider_left(const std::string& label) {
    const auto& r = probe_.rects.at(label);
    const glm::vec2 at{r[0].x + 2.0f, 0.5f * (r[0].y + r[1].y)};
    frame(at, false);
    frame(at, true);
    frame(at, false);
  }

  std::array<std::uint8_t, 4> pixel(glm::vec2 window_xy) {
    std::array<std::uint8_t, 4> rgba{};
    const int x = static_cast<int>(window_xy.x), y = kHeight - 1 - static_cast<int>(window_xy.y);  // GL rows go up
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glReadPixels(x, y, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    return rgba;
  }

  std::unique_ptr<GlContext> context_;
  std::unique_ptr<ViewSession> session_;
  std::unique_ptr<ImGuiLayer> ui_;
  UiProbe probe_;
  GLuint texture_ = 0, fbo_ = 0;
};

TEST_F(UiTest, PanelIsDrawnWhereItSaysAndNowhereElse) {
  frame();
  frame();  // ImGui sizes an auto-fitting window on its first frame and shows it on the next
  ASSERT_TRUE(probe_.rects.count("Pause"));
  const auto on_button = pixel(probe_.centre("Pause"));
  EXPECT_GT(on_button[0] + on_button[1] + on_button[2], 30) << "the Pause button left the framebuffer black";
  const auto far_corner = pixel({kWidth - 4.0f, kHeight - 4.0f});
  EXPECT_EQ(far_corner[0] + far_corner[1] + far_corner[2], 0) << "the panel covered the whole framebuffer";
}

TEST_F(UiTest, PanelClaimsTheMouseOnlyOverItself) {
  frame();
  frame();
  frame(probe_.centre("Pause"));
  frame(probe_.centre("Pause"));
  EXPECT_TRUE(ui_->wants_mouse());
  frame({kWidth - 10.0f, kHeight - 10.0f});
  frame({kWidth - 10.0f, kHeight - 10.0f});
  EXPECT_FALSE(ui_->wants_mouse()) << "the camera would not get drags over the scene";
}

TEST_F(UiTest, PauseHoldsTheSceneAndStepAdvancesOneFrame) {
  Profiler profiler(16, false);
  session_->advance(1.0f / 30.0f, profiler);
  frame();
  frame();
  click("Pause");
  ASSERT_TRUE(session_->panel().paused);
  const std::uint64_t held = state_hash(session_->scene());
  EXPECT_EQ(session_->advance(0.5f, profiler), 0.0f);
  EXPECT_EQ(state_hash(session_->scene()), held) << "a paused scene moved";
  click("Step");
  EXPECT_EQ(session_->panel().step_requests, 1);
  EXPECT_FLOAT_EQ(session_->advance(0.5f, profiler), 1.0f / 30.0f);
  EXPECT_NE(state_hash(session_->scene()), held) << "a single step did not move the scene";
  EXPECT_EQ(session_->panel().step_requests, 0);
  click("Pause");  // now labelled Resume, same place
  EXPECT_FALSE(session_->panel().paused);
}

TEST_F(UiTest, LevelComboSwitchesTheSceneLevel) {
  frame();
  frame();
  ASSERT_EQ(session_->scene().skin.level, DetailLevel::mesh(0));
  click("level");  // opens the combo; its items are drawn (and probed) from the next frame
  frame();
  ASSERT_TRUE(probe_.rects.count("level:2")) << "the combo did not list level 2";
  click("level:2");
  EXPECT_EQ(session_->scene().skin.level, DetailLevel::mesh(2));
}

TEST_F(UiTest, SkinningComboSwitchesTheSceneMode) {
  frame();
  frame();
  ASSERT_EQ(session_->scene().skin.mode, SkinningMode::Linear);
  click("skinning");  // opens the combo; its items are probed from the next frame
  frame();
  ASSERT_TRUE(probe_.rects.count("skinning:dqs")) << "the combo did not list dual quaternions";
  click("skinning:dqs");
  EXPECT_EQ(session_->scene().skin.mode, SkinningMode::DualQuaternion);
}

TEST_F(UiTest, MuscleGainSliderReachesTheScene) {
  ASSERT_TRUE(session_->scene().has_muscles());
  frame();
  frame();
  click("tab:Muscles");
  frame();
  ASSERT_TRUE(probe_.rects.count("all muscles")) << "the muscle section did not open";
  EXPECT_FLOAT_EQ(session_->scene().skin.gains.global, 1.0f);
  press_slider_left("all muscles");
  EXPECT_LT(session_->scene().skin.gains.global, 0.05f);
  click("Reset gains");
  EXPECT_FLOAT_EQ(session_->scene().skin.gains.global, 1.0f);
}

TEST_F(UiTest, GaitSliderReachesTheWalkGenerator) {
  ASSERT_EQ(session_->scene().motion.source, MotionSource::Walk);
  frame();
  frame();
  click("tab:Gait");
  frame();
  ASSERT_TRUE(probe_.rects.count("arm swing"));
  ASSERT_GT(session_->scene().motion.style.arm_swing, 0.0f);
  press_slider_left("arm swing");
  EXPECT_EQ(session_->scene().motion.style.arm_swing, 0.0f);
  click("Default gait");
  EXPECT_EQ(session_->scene().motion.style.arm_swing, GaitStyle{}.arm_swing);
}

TEST_F(UiTest, NewCrowdHasTheAskedSizeAndKeepsTheUsersSettings) {
  Crowd& before = session_->scene();
  set_detail_level(before, DetailLevel::mesh(1));
  MuscleGains gains;
  gains.global = 2.5f;
  set_muscle_gains(before, gains);
  before.motion.style.arm_swing = 0.3f;
  before.lod.policy.hysteresis = 1.5f;
  frame();
  frame();
  session_->panel().walkers = 7;
  click("New crowd");
  ASSERT_TRUE(session_->panel().rebuild_requested);
  ASSERT_TRUE(session_->apply_crowd_request());
  EXPECT_FALSE(session_->panel().rebuild_requested);
  const Crowd& after = session_->scene();
  EXPECT_EQ(after.walker_count(), 7u);
  EXPECT_EQ(after.skin.level, DetailLevel::mesh(1));
  EXPECT_FLOAT_EQ(after.skin.gains.global, 2.5f);
  EXPECT_FLOAT_EQ(session_->scene().motion.style.arm_swing, 0.3f);
  EXPECT_FLOAT_EQ(session_->scene().lod.policy.hysteresis, 1.5f);
  EXPECT_FALSE(session_->apply_crowd_request()) << "one request, one new crowd";
  // Paused before the first frame, the new crowd still gets skinned bodies to draw.
  session_->panel().paused = true;
  Profiler profiler(16, false);
  session_->advance(0.1f, profiler);
  EXPECT_EQ(current_skinned(session_->scene()).walkers, 7u);
}

TEST_F(UiTest, BindingTabStartsAndStopsTheEditor) {
  frame();
  frame();
  click("tab:Binding");
  frame();
  ASSERT_TRUE(probe_.rects.count("Edit binding"));
  click("Edit binding");
  session_->apply_binding_requests();
  ASSERT_TRUE(session_->panel().binding.active);
  frame();
  ASSERT_TRUE(probe_.rects.count("Bind selection")) << "the editing controls did not appear";
  click("joint");
  frame();
  ASSERT_TRUE(probe_.rects.count("joint:l_hip"));
  click("joint:l_hip");
  EXPECT_EQ(session_->panel().binding.joint, session_->scene().rig().skeleton.find_joint("l_hip"));
  click("Done");
  session_->apply_binding_requests();
  EXPECT_FALSE(session_->panel().binding.active);
}

TEST(ViewSessionCrowd, AFailedNewCrowdKeepsTheOldOneAndSaysWhy) {
  // A skeleton file that disappears after the first crowd was built from it.
  const test::TempDir tmp("strata_ui_test");
  const auto path = tmp / "skeleton.x3d";
  std::filesystem::copy_file(std::filesystem::path(STRATA_TEST_DATA) / "../../data/default_skeleton.x3d", path,
                             std::filesystem::copy_options::overwrite_existing);
  SceneOptions o;
  o.walkers = 2;
  o.threads = 1;
  o.skeleton = path.string();
  ViewSession session(o);
  std::filesystem::remove(path);
  session.panel().walkers = 5;
  session.panel().rebuild_requested = true;
  EXPECT_FALSE(session.apply_crowd_request());
  EXPECT_EQ(session.scene().walker_count(), 2u);
  EXPECT_NE(session.panel().last_message.find("no new crowd"), std::string::npos) << session.panel().last_message;
  EXPECT_NE(session.panel().last_message.find(path.filename().string()), std::string::npos)
      << "the reason names the file";
  EXPECT_FALSE(session.panel().rebuild_requested) << "one failed request is not retried every frame";
}

TEST(TimingHistory, KeepsTheLastFramesOfEverySystemInFrameOrder) {
  SceneOptions options;
  options.walkers = 2;
  options.threads = 1;
  ViewSession session(options);
  Profiler profiler(8, false);
  TimingHistory history(5);
  for (int f = 0; f < 9; ++f) {
    profiler.begin_frame();
    step(session.scene(), 1.0f / 30.0f, profiler);
    profiler.end_frame();
    history.push(profiler);
  }
  std::vector<std::string> names;
  for (const auto& s : history.series()) {
    names.push_back(s.name);
    EXPECT_EQ(s.ms.size(), 5u) << s.name;
    for (float ms : s.ms) EXPECT_GE(ms, 0.0f) << s.name;
  }
  const auto at = [&](const char* n) { return std::find(names.begin(), names.end(), n) - names.begin(); };
  ASSERT_LT(at("skin"), static_cast<long>(names.size()));
  EXPECT_LT(at("locomotion"), at("skin")) << "series are in the frame script's order";
}

}  // namespace
}  // namespace strata

// ---- The binding editor as the viewer drives it (no window: ViewSession with a scripted mouse) ----

namespace strata {
namespace {

struct EditorRig {
  explicit EditorRig(std::size_t walkers = 1) : session(options(walkers)) {
    session.panel().binding.rest_pose = true;  // still walkers in the rest pose
    session.apply_crowd_request();
    session.panel().binding.activate_requested = true;
    session.apply_binding_requests();
    session.advance(0.0f, profiler);
    glm::vec3 lo, hi;
    if (body_bounds(session.scene(), lo, hi)) camera.frame_box(lo, hi, aspect());
    view_projection = camera.projection(aspect()) * camera.view();
  }
  static SceneOptions options(std::size_t walkers) {
    SceneOptions o;
    o.walkers = walkers;
    o.threads = 1;
    return o;
  }
  float aspect() const { return static_cast<float>(viewport.x) / static_cast<float>(viewport.y); }
  void press_release(glm::vec2 from, glm::vec2 to, bool shift = false) {
    EditorMouse m;
    m.cursor = from;
    m.pressed = m.down = true;
    m.shift = shift;
    session.binding_mouse(m, view_projection, viewport);
    m = {};
    m.cursor = to;
    m.released = true;
    m.shift = shift;
    session.binding_mouse(m, view_projection, viewport);
  }
  const SkinBinding& level_binding(int level = 0) const {
    return session.scene().rig().body->levels[static_cast<std::size_t>(level)].binding;
  }

  ViewSession session;
  Profiler profiler{16, false};
  OrbitCamera camera;
  glm::ivec2 viewport{800, 600};
  glm::mat4 view_projection{1.0f};
};

TEST(BindingEditorSession, StartsOnAMeshLevelPausedWithAJoint) {
  EditorRig rig;
  const BindingEditState& b = rig.session.panel().binding;
  ASSERT_TRUE(b.active);
  EXPECT_EQ(b.level, 0);
  EXPECT_TRUE(rig.session.panel().paused);
  EXPECT_GE(b.joint, 0);
  ASSERT_NE(rig.session.binding_editor(), nullptr);
}

TEST(BindingEditorSession, ClickBindShowsSavesAndUndoes) {
  EditorRig rig;
  BindingEditState& b = rig.session.panel().binding;
  b.tool = BindingEditState::Tool::Click;
  rig.press_release({400.0f, 300.0f}, {400.0f, 300.0f});  // the middle of the framed body
  ASSERT_EQ(b.selected, 1u) << "a click on the body picks one vertex";
  const std::uint32_t v = rig.session.binding_editor()->selection().ids().at(0);
  const Skeleton skeleton = rig.session.scene().rig().skeleton;  // a copy: binding replaces the rig
  const int joint = skeleton.find_joint("l_shoulder");
  ASSERT_GE(joint, 0);
  const SkinBinding before = rig.level_binding();
  b.joint = joint;
  b.bind_requested = true;
  rig.session.apply_binding_requests();
  // The crowd deforms with the new weights at once: the scene's body carries them.
  const SkinBinding after = rig.level_binding();
  std::vector<int> joints;
  for (int k = 0; k < kMaxInfluences; ++k)
    if (after.weights[v][k] > 0.0f) joints.push_back(after.joints[v][k]);
  EXPECT_NE(std::find(joints.begin(), joints.end(), joint), joints.end());
  for (int j : joints) EXPECT_TRUE(j == joint || j == skeleton.parents[static_cast<std::size_t>(joint)]);
  EXPECT_EQ(b.edits, 1u);
  EXPECT_EQ(b.selected, 0u) << "a bound selection is cleared for the next pick";
  // The weights show: the chosen joint's heat on the edited vertex differs from an untouched far vertex.
  std::vector<BodyDrawInput> draws = body_draw_inputs(rig.session.scene());
  rig.session.colour_draws(draws);
  ASSERT_EQ(draws.size(), 1u);
  ASSERT_NE(draws[0].rgba, nullptr);
  // Saved, the overrides file reproduces the edited binding from scratch.
  const test::TempDir tmp("strata_ui_test");
  const auto path = tmp / "overrides.json";
  b.save_path = path.string();
  b.save_requested = true;
  rig.session.apply_binding_requests();
  ASSERT_TRUE(std::filesystem::exists(path)) << rig.session.panel().last_message;
  const BindingTables reloaded = load_binding_overrides_file(path.string(), shipped_binding_tables());
  // set_body replaced the rig: fetch its parts afresh.
  const Rig& edited_rig = rig.session.scene().rig();
  const SkinBinding rebound = bind_three_step(edited_rig.body->levels[0].mesh, edited_rig.skeleton, reloaded);
  EXPECT_EQ(rebound.joints, after.joints);
  EXPECT_EQ(rebound.weights, after.weights);
  b.undo_requested = true;
  rig.session.apply_binding_requests();
  EXPECT_EQ(rig.level_binding().joints, before.joints);
  EXPECT_EQ(rig.level_binding().weights, before.weights);
}

TEST(BindingEditorSession, ClickPicksOnTheWalkerUnderTheCursor) {
  EditorRig rig(4);
  const SkinnedCrowd& s = current_skinned(rig.session.scene());
  ASSERT_EQ(s.walkers, 4u);
  const auto project = [&](const glm::vec3& p) {
    const glm::vec4 c = rig.view_projection * glm::vec4(p, 1.0f);
    return glm::vec2{(c.x / c.w * 0.5f + 0.5f) * 800.0f, (0.5f - c.y / c.w * 0.5f) * 600.0f};
  };
  const std::vector<std::uint32_t>& original = current_layout(rig.session.scene()).original;
  for (std::size_t k = 0; k < s.walkers; ++k) {
    // Aim at the walker's pelvis height: the centre of its bounds.
    glm::vec3 lo = s.position(k, 0), hi = lo;
    for (std::size_t i = 0; i < s.vertex_count; ++i) lo = glm::min(lo, s.position(k, i)), hi = glm::max(hi, s.position(k, i));
    const glm::vec2 at = project(0.5f * (lo + hi));
    rig.press_release(at, at);
    ASSERT_EQ(rig.session.panel().binding.selected, 1u) << "walker " << k;
    const std::uint32_t v = rig.session.binding_editor()->selection().ids().at(0);
    const auto layout_index = static_cast<std::size_t>(
        std::find(original.begin(), original.end(), v) - original.begin());
    EXPECT_LT(glm::length(project(s.position(k, layout_index)) - at), 20.0f)
        << "the picked vertex is not on walker " << k << " under the cursor";
  }
}

TEST(BindingEditorSession, BoxTakesVisibleVerticesUnlessSelectingThrough) {
  EditorRig rig;
  BindingEditState& b = rig.session.panel().binding;
  b.tool = BindingEditState::Tool::Box;
  rig.press_release({0.0f, 0.0f}, {800.0f, 600.0f});
  const std::size_t visible = b.selected;
  const std::size_t total = rig.level_binding().vertex_count();
  EXPECT_GT(visible, total / 5) << "the front of the body";
  EXPECT_LT(visible, total * 7 / 10) << "the back is hidden";
  b.select_through = true;
  rig.press_release({0.0f, 0.0f}, {800.0f, 600.0f});
  EXPECT_GT(b.selected, visible + total / 5) << "select through takes the back too";
  // Shift adds a second box to the first; a box on empty ground adds nothing.
  b.select_through = false;
  rig.press_release({0.0f, 0.0f}, {400.0f, 600.0f});
  const std::size_t left = b.selected;
  rig.press_release({400.0f, 0.0f}, {800.0f, 600.0f}, true);
  EXPECT_GT(b.selected, left);
}

TEST(BindingEditorSession, BrushPaintsAlongTheDrag) {
  EditorRig rig;
  BindingEditState& b = rig.session.panel().binding;
  b.tool = BindingEditState::Tool::Brush;
  b.brush_radius_px = 10.0f;
  EditorMouse m;
  m.cursor = {400.0f, 250.0f};
  m.pressed = m.down = true;
  rig.session.binding_mouse(m, rig.view_projection, rig.viewport);
  const std::size_t dab = b.selected;
  EXPECT_GT(dab, 0u);
  m.pressed = false;
  for (float y = 260.0f; y <= 350.0f; y += 10.0f) {
    m.cursor.y = y;
    rig.session.binding_mouse(m, rig.view_projection, rig.viewport);
  }
  m.down = false;
  m.released = true;
  rig.session.binding_mouse(m, rig.view_projection, rig.viewport);
  EXPECT_GT(b.selected, 3 * dab) << "a stroke covers more than one dab";
  EXPECT_FALSE(b.dragging);
  // A minimised window (empty framebuffer) picks nothing and throws nothing.
  m = {};
  m.pressed = m.down = true;
  EXPECT_NO_THROW(rig.session.binding_mouse(m, rig.view_projection, {0, 0}));
}

TEST(BindingEditorSession, StartsFromTheOverridesFileTheSceneWasBoundWith) {
  const test::TempDir tmp("strata_ui_test");
  const auto path = tmp / "start.json";
  {
    std::ofstream f(path);
    f << R"({"overrides": [{"name": "ball", "sphere": {"center": [0, 1, 0], "radius": 0.1}, "joints": ["vl5"]}]})";
  }
  SceneOptions o = EditorRig::options(1);
  o.binding_overrides = path.string();
  ViewSession session(o);
  EXPECT_EQ(session.panel().binding.save_path, path.string()) << "Save goes back to the file being edited";
  session.panel().binding.activate_requested = true;
  session.apply_binding_requests();
  ASSERT_TRUE(session.panel().binding.active);
  ASSERT_EQ(session.binding_tables().overrides.size(), 1u);
  EXPECT_EQ(session.binding_tables().overrides[0].name, "ball");
}

TEST(BindingEditorSession, EditsSurviveANewCrowdAndFollowTheLevel) {
  EditorRig rig;
  BindingEditState& b = rig.session.panel().binding;
  b.tool = BindingEditState::Tool::Box;
  rig.press_release({300.0f, 200.0f}, {500.0f, 400.0f});
  ASSERT_GT(b.selected, 0u);
  b.joint = rig.session.scene().rig().skeleton.find_joint("r_hip");
  b.bind_requested = true;
  rig.session.apply_binding_requests();
  const SkinBinding edited = rig.level_binding();
  rig.session.panel().walkers = 3;
  rig.session.panel().rebuild_requested = true;
  ASSERT_TRUE(rig.session.apply_crowd_request());
  EXPECT_EQ(rig.session.scene().walker_count(), 3u);
  EXPECT_EQ(rig.level_binding().weights, edited.weights) << "a new crowd lost the edits";
  EXPECT_TRUE(b.active) << "editing goes on in the new crowd";
  // Another mesh level: the editor follows it, and the file keeps both levels' edits apart.
  set_detail_level(rig.session.scene(), DetailLevel::mesh(2));
  rig.session.apply_binding_requests();
  EXPECT_TRUE(b.active);
  EXPECT_EQ(b.level, 2);
  EXPECT_EQ(rig.session.binding_tables().overrides.size(), shipped_binding_tables().overrides.size() + 1);
  set_detail_level(rig.session.scene(), DetailLevel::automatic());
  rig.session.apply_binding_requests();
  EXPECT_FALSE(b.active) << "weights cannot be edited on the automatic mix of levels";
}

}  // namespace
}  // namespace strata

// ---- strata view without a window ----

namespace strata {
namespace {

TEST(ViewHeadless, SavesTheSceneWithThePanelAndRejectsAnUnknownJoint) {
  const test::TempDir tmp("strata_ui_test");
  const auto png = tmp / "view.png";
  const test::CliResult ok = test::run_strata("view --headless-png " + png.string() +
                                              " --walkers 1 --rest --frames 3 --width 320 --height 240 "
                                              "--edit-binding l_hip",
                                              "EGL_LOG_LEVEL=fatal");
  ASSERT_EQ(ok.status, 0) << ok.out;
  EXPECT_NE(ok.out.find("3 frames, 1 walkers"), std::string::npos) << ok.out;
  ASSERT_TRUE(std::filesystem::exists(png));
  EXPECT_GT(std::filesystem::file_size(png), 1000u);
  std::filesystem::remove(png);
  const test::CliResult bad =
      test::run_strata("view --headless-png " + png.string() + " --walkers 1 --frames 1 --edit-binding no_such_joint",
                       "EGL_LOG_LEVEL=fatal");
  EXPECT_EQ(bad.status, 1);
  EXPECT_NE(bad.out.find("no joint 'no_such_joint'"), std::string::npos) << bad.out;
  EXPECT_FALSE(std::filesystem::exists(png)) << "nothing written on an error";
}

TEST(BindingEditorSession, RestPoseOptionIsNotUndoneByThePanel) {
  SceneOptions o = EditorRig::options(1);
  o.rest = true;
  ViewSession session(o);
  EXPECT_TRUE(session.panel().binding.rest_pose);
  EXPECT_FALSE(session.apply_crowd_request()) << "--rest rebuilt the crowd on the first frame";
}

}  // namespace
}  // namespace strata
