// step(): the stages it runs for each motion source and level, the FrameProfile it returns, and a bad dt refused
// before anything is written.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "io/hanim_loader.h"
#include "rig/body_rig.h"
#include "rig/muscle_binding.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/state_hash.h"
#include "scene/step.h"

namespace strata {
namespace {

std::unique_ptr<Crowd> walking_crowd(std::size_t walkers) {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  rig.muscles = default_muscle_rig();
  auto crowd = std::make_unique<Crowd>(std::move(rig));
  CrowdConfig config;
  config.walkers = walkers;
  config.motion = MotionSource::Walk;
  spawn_crowd(*crowd, config);
  return crowd;
}

bool ran(const FrameProfile& p, Stage s) { return p.ran[static_cast<std::size_t>(s)]; }

TEST(Step, AWalkingFrameRunsItsStagesInOrderAndTimesEach) {
  auto crowd = walking_crowd(4);
  Profiler profiler(4, true);
  profiler.begin_frame();
  const FrameProfile p = step(*crowd, 1.0f / 30.0f, profiler);
  profiler.end_frame();
  for (Stage s : {Stage::Locomotion, Stage::Ik, Stage::Fk, Stage::Muscle, Stage::Lod, Stage::Skin}) {
    EXPECT_TRUE(ran(p, s)) << stage_name(s);
    EXPECT_GE(p.stage_ms(s), 0.0) << stage_name(s);
  }
  for (Stage s : {Stage::Animation, Stage::Mocap, Stage::Subdiv}) {
    EXPECT_FALSE(ran(p, s)) << stage_name(s);
    EXPECT_EQ(p.stage_ms(s), 0.0) << stage_name(s);
  }
  double sum = 0.0;
  for (double ms : p.ms) sum += ms;
  EXPECT_LE(sum, p.total_ms + 1e-6);
  EXPECT_EQ(p.walkers_per_level[0], 4u);
  // The profiler saw the same stages under the same names, in the script's order.
  std::vector<std::string> names;
  for (const SystemStats& s : profiler.stats()) names.push_back(s.name);
  const std::vector<std::string> expected = {"lod", "locomotion", "ik", "fk", "muscle", "skin"};
  EXPECT_EQ(names, expected);
}

TEST(Step, SubdivisionLevelsRefineInsteadOfSkinningAndNoBodySkinsNothing) {
  auto crowd = walking_crowd(2);
  Profiler profiler(4, false);
  set_detail_level(*crowd, DetailLevel::subdiv(1));
  FrameProfile p = step(*crowd, 1.0f / 30.0f, profiler);
  EXPECT_TRUE(ran(p, Stage::Subdiv));
  EXPECT_FALSE(ran(p, Stage::Skin));
  EXPECT_EQ(crowd->table(DetailSlot::Refined).size(), 2u);
  set_detail_level(*crowd, DetailLevel::none());
  EXPECT_EQ(crowd->table(DetailSlot::NoBody).size(), 2u) << "a level switch moves the walkers at once";
  EXPECT_TRUE(crowd->world.validate().empty());
  p = step(*crowd, 1.0f / 30.0f, profiler);
  EXPECT_FALSE(ran(p, Stage::Skin));
  EXPECT_FALSE(ran(p, Stage::Subdiv));
  EXPECT_EQ(crowd->table(DetailSlot::NoBody).size(), 2u);
  EXPECT_EQ(p.moved, 0u);
  for (const SkinnedCrowd& s : crowd->skinned) EXPECT_EQ(s.walkers, 0u);
}

TEST(Step, ANonFiniteOrNegativeDtIsRefusedBeforeAnythingChanges) {
  auto crowd = walking_crowd(3);
  Profiler profiler(4, false);
  step(*crowd, 1.0f / 30.0f, profiler);
  const std::uint64_t before = state_hash(*crowd);
  for (float dt : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -0.01f})
    EXPECT_THROW(step(*crowd, dt, profiler), std::invalid_argument) << dt;
  EXPECT_EQ(state_hash(*crowd), before);
}

}  // namespace
}  // namespace strata
