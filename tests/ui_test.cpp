// The viewer's control panel, driven headless: a real ImGui context drawn by its OpenGL 3 backend into an FBO of
// a Mesa EGL context, clicked with a scripted mouse at the rectangles the panel reports (UiProbe), acting on a
// real crowd scene through ViewSession. No window and no display needed.
#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <memory>
#include <vector>

#include "apps/view_session.h"
#include "components/body.h"
#include "profiling/profiler.h"
#include "render/gl_context.h"
#include "ui/imgui_layer.h"
#include "ui/view_panel.h"

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
    cli::SceneOptions options;
    options.walkers = 4;
    options.threads = 1;
    session_ = std::make_unique<cli::ViewSession>(options);
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
  std::unique_ptr<cli::ViewSession> session_;
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
  const std::uint64_t held = session_->scene().state_hash();
  EXPECT_EQ(session_->advance(0.5f, profiler), 0.0f);
  EXPECT_EQ(session_->scene().state_hash(), held) << "a paused scene moved";
  click("Step");
  EXPECT_EQ(session_->panel().step_requests, 1);
  EXPECT_FLOAT_EQ(session_->advance(0.5f, profiler), 1.0f / 30.0f);
  EXPECT_NE(session_->scene().state_hash(), held) << "a single step did not move the scene";
  EXPECT_EQ(session_->panel().step_requests, 0);
  click("Pause");  // now labelled Resume, same place
  EXPECT_FALSE(session_->panel().paused);
}

TEST_F(UiTest, LevelComboSwitchesTheSceneLevel) {
  frame();
  frame();
  ASSERT_EQ(session_->scene().body_level(), 0);
  click("level");  // opens the combo; its items are drawn (and probed) from the next frame
  frame();
  ASSERT_TRUE(probe_.rects.count("level:2")) << "the combo did not list level 2";
  click("level:2");
  EXPECT_EQ(session_->scene().body_level(), 2);
}

TEST_F(UiTest, MuscleGainSliderReachesTheScene) {
  ASSERT_TRUE(session_->scene().has_muscles());
  frame();
  frame();
  click("tab:Muscles");
  frame();
  ASSERT_TRUE(probe_.rects.count("all muscles")) << "the muscle section did not open";
  EXPECT_FLOAT_EQ(session_->scene().muscle_gains().global, 1.0f);
  press_slider_left("all muscles");
  EXPECT_LT(session_->scene().muscle_gains().global, 0.05f);
  click("Reset gains");
  EXPECT_FLOAT_EQ(session_->scene().muscle_gains().global, 1.0f);
}

TEST_F(UiTest, GaitSliderReachesTheWalkGenerator) {
  ASSERT_EQ(session_->scene().motion(), MotionSource::Walk);
  frame();
  frame();
  click("tab:Gait");
  frame();
  ASSERT_TRUE(probe_.rects.count("arm swing"));
  ASSERT_GT(session_->scene().style().arm_swing, 0.0f);
  press_slider_left("arm swing");
  EXPECT_EQ(session_->scene().style().arm_swing, 0.0f);
  click("Default gait");
  EXPECT_EQ(session_->scene().style().arm_swing, GaitStyle{}.arm_swing);
}

TEST_F(UiTest, NewCrowdHasTheAskedSizeAndKeepsTheUsersSettings) {
  CrowdScene& before = session_->scene();
  before.set_body_level(1);
  MuscleGains gains;
  gains.global = 2.5f;
  before.set_muscle_gains(gains);
  before.style().arm_swing = 0.3f;
  before.lod_policy().hysteresis = 1.5f;
  frame();
  frame();
  session_->panel().walkers = 7;
  click("New crowd");
  ASSERT_TRUE(session_->panel().rebuild_requested);
  ASSERT_TRUE(session_->apply_crowd_request());
  EXPECT_FALSE(session_->panel().rebuild_requested);
  const CrowdScene& after = session_->scene();
  EXPECT_EQ(after.walker_count(), 7u);
  EXPECT_EQ(after.body_level(), 1);
  EXPECT_FLOAT_EQ(after.muscle_gains().global, 2.5f);
  EXPECT_FLOAT_EQ(session_->scene().style().arm_swing, 0.3f);
  EXPECT_FLOAT_EQ(session_->scene().lod_policy().hysteresis, 1.5f);
  EXPECT_FALSE(session_->apply_crowd_request()) << "one request, one new crowd";
  // Paused before the first frame, the new crowd still gets skinned bodies to draw.
  session_->panel().paused = true;
  Profiler profiler(16, false);
  session_->advance(0.1f, profiler);
  EXPECT_EQ(session_->scene().skinned().walkers, 7u);
}

TEST(TimingHistory, KeepsTheLastFramesOfEverySystemInFrameOrder) {
  cli::SceneOptions options;
  options.walkers = 2;
  options.threads = 1;
  cli::ViewSession session(options);
  Profiler profiler(8, false);
  TimingHistory history(5);
  for (int f = 0; f < 9; ++f) {
    profiler.begin_frame();
    session.scene().simulate(1.0f / 30.0f, profiler);
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
