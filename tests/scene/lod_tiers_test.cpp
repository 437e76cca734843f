// The impostor tier and simulation level of detail (scene/crowd.h, scene/step.h): far walkers live in the narrow
// impostor table and only keep their gait clock, exactly as walking walkers keep it; a walker coming back gets a
// settled pose on its first frame; the mesh budget keeps the nearest; clip crowds never become impostors; skinned
// storage follows the meshes, not the crowd; results do not depend on the thread count.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "io/hanim_loader.h"
#include "rig/body_rig.h"
#include "rig/muscle_binding.h"
#include "scene/body_settings.h"
#include "scene/spawn.h"
#include "scene/state_hash.h"
#include "scene/step.h"
#include "systems/pose_gather.h"

namespace strata {
namespace {

std::unique_ptr<Crowd> walking_crowd(std::size_t walkers, DetailLevel level) {
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  rig.muscles = default_muscle_rig();
  auto crowd = std::make_unique<Crowd>(std::move(rig));
  set_detail_level(*crowd, level);
  CrowdConfig config;
  config.walkers = walkers;
  config.motion = MotionSource::Walk;
  spawn_crowd(*crowd, config);
  return crowd;
}

// A camera at `eye` looking at the track's centre, 720 px high, 0.8 rad vertical field of view (OrbitCamera's).
LodView view_from(const glm::vec3& eye) {
  LodView v;
  const glm::mat4 projection = glm::perspective(0.8f, 16.0f / 9.0f, 0.05f, 2000.0f);
  v.view_projection = projection * glm::lookAt(eye, glm::vec3(0.0f, 1.0f, 0.0f), glm::vec3(0, 1, 0));
  v.eye = eye;
  v.focal_px = 720.0f / (2.0f * std::tan(0.4f));
  return v;
}

std::size_t meshes(const Crowd& c) {
  std::size_t n = 0;
  for (int k = 0; k < kMaxMeshLevels; ++k) n += c.table(mesh_slot(k)).size();
  return n;
}

// Where walker `e` is and its gait phase.
struct Clock {
  float placement[5];
  float phase, distance;
};
Clock clock_of(const Crowd& c, Entity e) {
  const EntityLocation at = c.world.location(e);
  const SoaTable& t = c.world.table(at.table);
  Clock k{};
  for (std::uint32_t i = 0; i < 5; ++i) k.placement[i] = t.f32(kWalkerPlacement, i)[at.block];
  k.phase = t.f32(kWalkerGait, kGaitPhase)[at.block];
  k.distance = t.f32(kWalkerGait, kGaitDistance)[at.block];
  return k;
}

TEST(LodTiers, TheImpostorTableIsNarrowAndHoldsNoPose) {
  auto crowd = walking_crowd(300, DetailLevel::automatic());
  const SoaTable& light = crowd->table(DetailSlot::Impostor);
  const SoaTable& wide = crowd->table(DetailSlot::Mesh0);
  EXPECT_TRUE(is_light_walker_table(light));
  EXPECT_FALSE(is_light_walker_table(wide));
  std::size_t light_bytes = 0, wide_bytes = 0;
  for (const FieldDesc& f : light.fields()) light_bytes += f.width * 4;
  for (const FieldDesc& f : wide.fields()) wide_bytes += f.width * 4;
  EXPECT_LE(light_bytes, 400u);
  EXPECT_GT(wide_bytes, 10 * light_bytes) << "a posed walker holds matrices for every joint";
  // The fields an impostor needs keep their width, so moving a walker in keeps them.
  for (const std::uint32_t f : {kWalkerPlacement, kWalkerClock, kWalkerGait, kWalkerPath, kWalkerRootTranslation})
    EXPECT_EQ(light.fields()[f].width, wide.fields()[f].width) << light.fields()[f].name;
  // A walking crowd under auto spawns its walkers as impostors: no wide row is held for them.
  EXPECT_EQ(light.size(), 300u);
  EXPECT_LT(wide.capacity(), 300u) << "spawning passed each walker through the wide table one at a time";
}

// Impostors skip IK, FK and muscles but keep position, heading and gait phase exactly as the whole walk keeps
// them: the same clock code runs in both.
TEST(LodTiers, FarWalkersKeepTheirPlaceAndPhaseExactly) {
  auto far = walking_crowd(12, DetailLevel::automatic());
  auto whole = walking_crowd(12, DetailLevel::mesh(2));
  far->lod.view = view_from({0.0f, 30.0f, 400.0f});
  Profiler profiler(4, false);
  FrameProfile p;
  for (int f = 0; f < 90; ++f) {
    p = step(*far, 1.0f / 30.0f, profiler);
    step(*whole, 1.0f / 30.0f, profiler);
  }
  EXPECT_EQ(far->table(DetailSlot::Impostor).size(), 12u);
  EXPECT_EQ(p.impostors, 12u);
  EXPECT_FALSE(p.ran[static_cast<std::size_t>(Stage::Ik)] && p.stage_ms(Stage::Ik) > 0.0 && meshes(*far) > 0);
  EXPECT_EQ(far->skinned[slot_index(DetailSlot::Mesh0)].walkers + far->skinned[slot_index(DetailSlot::Mesh2)].walkers, 0u);
  const std::vector<Entity> a = far->world.entities(), b = whole->world.entities();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t w = 0; w < a.size(); ++w) {
    const Clock ka = clock_of(*far, a[w]), kb = clock_of(*whole, b[w]);
    for (int i = 0; i < 5; ++i) EXPECT_EQ(ka.placement[i], kb.placement[i]) << "walker " << w << " component " << i;
    EXPECT_EQ(ka.phase, kb.phase) << w;
    EXPECT_EQ(ka.distance, kb.distance) << w;
  }
}

// A walker that comes back from the impostor tier is posed on its first frame: its joints where the same walker's
// are in a crowd that kept it a mesh all along (the walk restarts from phase and path position), with no NaN.
TEST(LodTiers, AWalkerBackFromImpostorIsPosedOnItsFirstFrame) {
  auto tiered = walking_crowd(6, DetailLevel::automatic());
  auto whole = walking_crowd(6, DetailLevel::mesh(0));
  tiered->lod.policy.mesh_budget = 0;
  tiered->lod.view = view_from({0.0f, 30.0f, 400.0f});  // far: every walker an impostor
  Profiler profiler(4, false);
  for (int f = 0; f < 45; ++f) {
    step(*tiered, 1.0f / 30.0f, profiler);
    step(*whole, 1.0f / 30.0f, profiler);
  }
  ASSERT_EQ(tiered->table(DetailSlot::Impostor).size(), 6u);
  tiered->lod.view = view_from({0.0f, 4.0f, 14.0f});  // near, and a lower threshold: meshes again
  tiered->lod.policy.impostor_px = 20.0f;
  const FrameProfile p = step(*tiered, 1.0f / 30.0f, profiler);
  step(*whole, 1.0f / 30.0f, profiler);
  ASSERT_EQ(tiered->table(DetailSlot::Impostor).size(), 0u);
  EXPECT_EQ(p.moved, 6u);
  std::size_t compared = 0;
  float worst = 0.0f;
  for (int k = 0; k < kMaxMeshLevels; ++k) {
    const SoaTable& t = tiered->table(mesh_slot(k));
    WalkerLanes lanes = walker_lanes(const_cast<SoaTable&>(t), tiered->joint_count());
    std::vector<glm::vec3> joints;
    gather_joint_positions(lanes, joints);
    for (std::size_t row = 0; row < t.size(); ++row) {
      const Entity e = t.owner(static_cast<std::uint32_t>(row));
      // The same walker of the other crowd: both crowds issued their entities in the same order.
      const std::vector<Entity> ids = whole->world.entities();
      const auto it = std::find_if(ids.begin(), ids.end(), [&](Entity x) { return x.index == e.index; });
      ASSERT_NE(it, ids.end());
      const EntityLocation wat = whole->world.location(*it);
      WalkerLanes wl = walker_lanes(whole->world.table(wat.table), whole->joint_count());
      std::vector<glm::vec3> wj;
      gather_joint_positions(wl, wj);
      const std::size_t n = tiered->joint_count();
      for (std::size_t j = 0; j < n; ++j) {
        const glm::vec3 a = joints[row * n + j], b = wj[wat.block * n + j];
        ASSERT_TRUE(std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z));
        worst = std::max(worst, glm::length(a - b));
      }
      ++compared;
    }
  }
  EXPECT_EQ(compared, 6u);
  // The restart re-derives footprints and the pelvis from phase and distance: the same pose up to the pelvis
  // height's memory of the last heel strike (a few millimetres) and a swing already under way, which leaves
  // from the foot rolled for the pelvis' highest height where the walk rolled it for the pelvis as it then was
  // (lower, in double support): measured 2.8 cm at the swing foot.
  EXPECT_LT(worst, 0.035f) << "largest joint distance from the walker that never left its mesh";
}

TEST(LodTiers, TheMeshBudgetKeepsTheNearest) {
  auto crowd = walking_crowd(30, DetailLevel::automatic());
  crowd->lod.policy.mesh_budget = 5;
  crowd->lod.policy.impostor_px = 1.0f;  // every visible walker qualifies for a mesh by size
  crowd->lod.view = view_from({0.0f, 3.0f, 25.0f});
  Profiler profiler(4, false);
  const FrameProfile p = step(*crowd, 1.0f / 30.0f, profiler);
  EXPECT_EQ(meshes(*crowd), 5u);
  EXPECT_EQ(p.walkers_per_level[0] + p.walkers_per_level[1] + p.walkers_per_level[2], 5u);
  EXPECT_GT(crowd->lod.over_budget, 0u);
  EXPECT_EQ(crowd->lod.over_budget, crowd->table(DetailSlot::Impostor).size());
  // No impostor is nearer than the farthest mesh (distances from the placements the lod stage read: this frame's
  // start, one dt before the placements now, so a margin of a frame's walk).
  const glm::vec3 eye = crowd->lod.view->eye;
  auto distance = [&](const SoaTable& t, std::size_t b) {
    const glm::vec3 root = crowd->rig().skeleton.centers[0] +
                           glm::vec3(t.f32(kWalkerRootTranslation, 0)[b], t.f32(kWalkerRootTranslation, 1)[b],
                                     t.f32(kWalkerRootTranslation, 2)[b]);
    return glm::length(glm::vec3(t.f32(kWalkerPlacement, 0)[b], root.y * t.f32(kWalkerPlacement, 4)[b],
                                 t.f32(kWalkerPlacement, 2)[b]) - eye);
  };
  float farthest_mesh = 0.0f, nearest_impostor = 1e9f;
  for (int k = 0; k < kMaxMeshLevels; ++k)
    for (std::size_t b = 0; b < crowd->table(mesh_slot(k)).size(); ++b)
      farthest_mesh = std::max(farthest_mesh, distance(crowd->table(mesh_slot(k)), b));
  const SoaTable& imp = crowd->table(DetailSlot::Impostor);
  for (std::size_t b = 0; b < imp.size(); ++b) nearest_impostor = std::min(nearest_impostor, distance(imp, b));
  EXPECT_LE(farthest_mesh, nearest_impostor + 0.1f);
  // Skinned storage follows the meshes: five walkers' worth at most, whatever the crowd.
  std::size_t skinned = 0;
  for (int k = 0; k < kMaxMeshLevels; ++k) skinned += crowd->skinned[static_cast<std::size_t>(k)].walkers;
  EXPECT_EQ(skinned, 5u);
  EXPECT_TRUE(crowd->world.validate().empty());
}

TEST(LodTiers, ForcedImpostorsAndClipCrowds) {
  auto forced = walking_crowd(8, DetailLevel::impostor());
  forced->lod.view = view_from({0.0f, 3.0f, 12.0f});
  Profiler profiler(4, false);
  const FrameProfile p = step(*forced, 1.0f / 30.0f, profiler);
  EXPECT_EQ(meshes(*forced), 0u);
  EXPECT_EQ(forced->table(DetailSlot::Impostor).size() + forced->table(DetailSlot::Culled).size(), 8u);
  EXPECT_GT(forced->table(DetailSlot::Impostor).size(), 0u);
  EXPECT_FALSE(p.ran[static_cast<std::size_t>(Stage::Skin)] && p.walkers_per_level[0] > 0);

  // A clip crowd plays its own motion, not the baked walk: far walkers stay meshes under auto.
  Rig rig = to_rig(load_default_humanoid());
  rig.body = default_bound_body();
  Crowd clips(std::move(rig));
  set_detail_level(clips, DetailLevel::automatic());
  CrowdConfig config;
  config.walkers = 4;
  config.motion = MotionSource::Clip;
  spawn_crowd(clips, config);
  EXPECT_FALSE(crowd_may_use_impostors(clips));
  clips.lod.view = view_from({0.0f, 30.0f, 400.0f});
  step(clips, 1.0f / 30.0f, profiler);
  EXPECT_EQ(clips.table(DetailSlot::Impostor).size(), 0u);
  EXPECT_EQ(meshes(clips), 4u);
  EXPECT_EQ(initial_slot(clips), DetailSlot::Mesh0);
}

// Tiers change as the camera moves (walkers enter and leave the impostor tier, the budget cuts), and the state
// hash is the same with one thread as with two.
TEST(LodTiers, TieredCrowdsAreDeterministicWhateverTheThreadCount) {
  auto run = [](int threads) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    auto crowd = walking_crowd(150, DetailLevel::automatic());
    crowd->lod.policy.mesh_budget = 7;
    Profiler profiler(4, false);
    std::size_t moved = 0;
    for (int f = 0; f < 40; ++f) {
      crowd->lod.view = view_from({0.0f, 2.0f, 8.0f + 1.5f * static_cast<float>(f)});
      moved += step(*crowd, 1.0f / 30.0f, profiler).moved;
    }
    EXPECT_GT(moved, 0u);
    return state_hash(*crowd);
  };
  EXPECT_EQ(run(1), run(2));
}

}  // namespace
}  // namespace strata
