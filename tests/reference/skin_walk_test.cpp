// The default body's skin over the default walk (issue 4's last target): at every level the shipped three-step
// binding keeps every triangle the right way round in every frame, opens no seam and makes no NaN. It measures
// through the same code as `strata report skin` (apps/skin_walk.h), over the report's 2.5 s at 60 fps.
#include <gtest/gtest.h>

#include "reference/skin_walk.h"
#include "io/hanim_loader.h"
#include "rig/binding.h"
#include "rig/body_generator.h"
#include "tests/sanitizer_scale.h"

namespace strata {
namespace {

// Under the sanitizers the same 2.5 s are sampled at 20 fps (tests/sanitizer_scale.h): every code path, a third
// of the frames.
constexpr float kSeconds = 2.5f, kFps = static_cast<float>(test::trials_for_build(60, 3));
constexpr unsigned kFrames = static_cast<unsigned>(kSeconds * kFps);

TEST(SkinWalk, NoTriangleInvertsOverTheDefaultWalkAtAnyLevel) {
  const Rig rig = to_rig(load_default_humanoid());
  for (int l = 0; l < 3; ++l) {
    const Mesh& mesh = default_body().levels[static_cast<std::size_t>(l)];
    const BodyLevel level{mesh, bind_three_step(mesh, rig.skeleton, default_binding_tables())};
    const WalkSkinMetrics walk = measure_walk_skin(rig, level, kSeconds, kFps);
    EXPECT_EQ(walk.frames, kFrames);
    EXPECT_EQ(walk.inverted_triangles, 0u) << "level " << l << ": worst at frame " << walk.worst_frame;
    EXPECT_EQ(walk.seam_gap_max_m, 0.0) << "level " << l;
    EXPECT_EQ(walk.nan_count, 0u) << "level " << l;
  }
}

// The walk is demanding enough for the test above to mean something: without step 3 (the groin, foot and
// shoulder blends of data/binding_overrides.json) the same walk folds triangles.
TEST(SkinWalk, WithoutTheOverridesTheSameWalkFoldsTheGroin) {
  const Rig rig = to_rig(load_default_humanoid());
  const Mesh& mesh = default_body().levels[2];
  BindingOptions steps_one_and_two;
  steps_one_and_two.apply_overrides = false;
  const BodyLevel level{mesh, bind_three_step(mesh, rig.skeleton, default_binding_tables(), steps_one_and_two)};
  const WalkSkinMetrics walk = measure_walk_skin(rig, level, kSeconds, kFps);
  EXPECT_GT(walk.inverted_triangles, 10u);
  EXPECT_GE(walk.worst_frame, 0);
}

}  // namespace
}  // namespace strata
