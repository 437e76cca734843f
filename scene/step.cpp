#include "scene/step.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "rig/subdiv_topology.h"
#include "scene/body_settings.h"
#include "systems/animation_sample.h"
#include "systems/fk.h"
#include "systems/ik.h"
#include "systems/locomotion.h"
#include "systems/mocap_drive.h"
#include "systems/muscle.h"
#include "systems/job.h"
#include "systems/subdiv.h"

namespace strata {
namespace {

// Times one stage into the FrameProfile and, when profiling is compiled in, into the profiler under the stage's
// name (the same names the per-system tables and traces have always used).
class StageTimer {
 public:
  StageTimer(Profiler& profiler, FrameProfile& profile, Stage stage)
      :
#if STRATA_PROFILING
        timer_(profiler, profiler.intern(stage_name(stage))),
#endif
        profile_(profile), stage_(stage), start_(std::chrono::steady_clock::now()) {
    (void)profiler;
  }
  ~StageTimer() {
    const auto i = static_cast<std::size_t>(stage_);
    profile_.ms[i] += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
    profile_.ran[i] = true;
  }
  StageTimer(const StageTimer&) = delete;
  StageTimer& operator=(const StageTimer&) = delete;

 private:
#if STRATA_PROFILING
  Profiler::ScopedTimer timer_;
#endif
  FrameProfile& profile_;
  Stage stage_;
  std::chrono::steady_clock::time_point start_;
};

// Runs `system(table)` over every non-empty walker table, in slot order.
template <class System>
void for_each_table(Crowd& crowd, System&& system) {
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    SoaTable& t = crowd.world.table(crowd.tables[s]);
    if (t.size() > 0) system(t);
  }
}

// The level-of-detail stage: the table each walker is skinned from this frame, and the moves that put it there.
void lod_stage(Crowd& crowd, FrameProfile& profile) {
  CrowdLod& lod = crowd.lod;
  const DetailLevel level = crowd.skin.level;
  const int levels = crowd.rig().body ? static_cast<int>(crowd.rig().body->levels.size()) : 0;
  // Culling and levels need a camera; S levels are drawn whole (their cage pass has no per-walker subset).
  const bool decide = lod.view && (level.is_mesh() || level.is_automatic());
  const DetailSlot fixed_slot = initial_slot(crowd);
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    SoaTable& t = crowd.world.table(crowd.tables[s]);
    std::vector<std::uint8_t>& decided = lod.decided[s];
    if (decided.size() < t.size()) decided.resize(t.capacity());
    if (t.size() == 0) continue;
    if (!decide) {
      std::fill(decided.begin(), decided.begin() + static_cast<std::ptrdiff_t>(t.size()),
                static_cast<std::uint8_t>(fixed_slot));
      continue;
    }
    // The table a walker is in is its previous decision: hysteresis needs nothing else. Culled (and never seen)
    // walkers have none, so their first decision is the plain one.
    const int previous = s < static_cast<std::size_t>(kMaxMeshLevels) ? static_cast<int>(s) : -1;
    LodJob job;
    job.view = &*lod.view;
    job.policy = &lod.policy;
    job.body_height = crowd.skin.body_height;
    job.previous_level = previous;
    job.fixed_level = level.is_automatic() ? -1 : level.index();
    job.levels = levels;
    job.culled_slot = static_cast<std::uint8_t>(DetailSlot::Culled);
    const WalkerLanes lanes = walker_lanes(t, crowd.joint_count());
    job.walkers = lanes.count;
    job.stride = lanes.stride;
    job.placement = lanes.placement;
    job.world = lanes.world;
    job.decided = std::span<std::uint8_t>(decided.data(), t.size());
    if (!job.run()) throw std::logic_error("step: the level-of-detail job rejected table " + t.name());
  }
  // Apply the moves after every decision, so no walker is decided twice. Handles are stable across moves; rows
  // are not (swap-remove), so the movers are collected first.
  std::vector<std::pair<Entity, DetailSlot>>& moves = lod.moves;
  moves.clear();
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    const SoaTable& t = crowd.world.table(crowd.tables[s]);
    for (std::size_t b = 0; b < t.size(); ++b)
      if (lod.decided[s][b] != s)
        moves.emplace_back(t.owner(static_cast<std::uint32_t>(b)), static_cast<DetailSlot>(lod.decided[s][b]));
  }
  for (const auto& [walker, to] : moves) crowd.world.move(walker, crowd.tables[slot_index(to)]);
  profile.moved = moves.size();
}

}  // namespace

const char* stage_name(Stage stage) {
  switch (stage) {
    case Stage::Locomotion: return "locomotion";
    case Stage::Animation: return "animation";
    case Stage::Mocap: return "mocap";
    case Stage::Ik: return "ik";
    case Stage::Fk: return "fk";
    case Stage::Muscle: return "muscle";
    case Stage::Lod: return "lod";
    case Stage::Skin: return "skin";
    case Stage::Subdiv: return "subdiv";
  }
  return "?";
}

FrameProfile step(Crowd& crowd, float dt, Profiler& profiler) {
  if (!std::isfinite(dt) || dt < 0.0f) throw std::invalid_argument("step: dt must be finite and >= 0, got " + std::to_string(dt));
  FrameProfile profile;
  const auto start = std::chrono::steady_clock::now();
  const Rig& rig = crowd.rig();
  const CrowdMotion& m = crowd.motion;

  // 1-2. Motion: what drives the walkers picks the first systems.
  if (m.source == MotionSource::Walk && m.locomotion) {
    {
      StageTimer t(profiler, profile, Stage::Locomotion);
      for_each_table(crowd, [&](SoaTable& t) {
        run_or_throw(make_locomotion_job(*m.locomotion, m.paths, t, dt, m.style), "locomotion");
      });
    }
    StageTimer t(profiler, profile, Stage::Ik);
    for_each_table(crowd, [&](SoaTable& t) { run_or_throw(make_ik_job(rig.skeleton, m.locomotion->limbs, t), "ik"); });
  } else if (m.source == MotionSource::Mocap && m.mocap_rig) {
    {
      StageTimer t(profiler, profile, Stage::Mocap);
      for_each_table(crowd, [&](SoaTable& t) { run_or_throw(make_mocap_drive_job(*m.mocap_rig, t, dt), "mocap"); });
    }
    StageTimer t(profiler, profile, Stage::Ik);
    for_each_table(crowd, [&](SoaTable& t) { run_or_throw(make_ik_job(rig.skeleton, m.mocap_rig->limbs, t), "ik"); });
  } else {
    StageTimer t(profiler, profile, Stage::Animation);
    for_each_table(crowd, [&](SoaTable& t) { run_or_throw(make_animation_job(rig, t, dt), "animation"); });
  }
  // 3. Forward kinematics.
  {
    StageTimer t(profiler, profile, Stage::Fk);
    for_each_table(crowd, [&](SoaTable& t) { run_or_throw(make_fk_job(rig.skeleton, t), "fk"); });
  }
  // 4. Muscles.
  if (crowd.muscles_enabled()) {
    StageTimer t(profiler, profile, Stage::Muscle);
    for_each_table(crowd, [&](SoaTable& t) { run_or_throw(make_muscle_job(rig.muscles->set, t), "muscle"); });
  }
  // 5. Level of detail: which table each walker is skinned from.
  CrowdSkin& skin = crowd.skin;
  {
    StageTimer t(profiler, profile, Stage::Lod);
    lod_stage(crowd, profile);
  }
  // 6. Skin each level's table into that level's storage, or refine the cage.
  auto& counts = profile.walkers_per_level;
  // Storage of the slots not skinned this frame says so (their buffers stay allocated for the next switch).
  for (std::size_t s = 0; s < kDetailSlots; ++s) crowd.skinned[s].walkers = 0;
  if (skin.level.is_subdiv()) {
    StageTimer t(profiler, profile, Stage::Subdiv);  // cage skinning + refinement + normals
    SoaTable& table = crowd.table(DetailSlot::Refined);
    run_or_throw(make_subdiv_job(*skin.subdiv, table, crowd.skinned[slot_index(DetailSlot::Refined)],
                                 crowd.muscles_enabled() ? &skin.cage_muscles : nullptr, skin.mode),
                 "subdiv");
    counts[0] = table.size();
  } else if (!skin.level.is_none()) {
    StageTimer t(profiler, profile, Stage::Skin);
    for (int k = 0; k < kMaxMeshLevels; ++k) {
      SoaTable& table = crowd.table(mesh_slot(k));
      SkinnedCrowd& out = crowd.skinned[static_cast<std::size_t>(k)];
      counts[static_cast<std::size_t>(k)] = table.size();
      if (table.size() == 0) {
        out.walkers = 0;
        continue;
      }
      run_or_throw(make_skin_job(skin.layouts[static_cast<std::size_t>(k)], table, out, nullptr, skin.mode),
                   "skin");
    }
    counts[3] = crowd.table(DetailSlot::Culled).size();
  }
  crowd.lod.counts = counts;
  profile.total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return profile;
}

}  // namespace strata
