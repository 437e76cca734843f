#include "scene/step.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "rig/subdiv_topology.h"
#include "scene/body_settings.h"
#include "scene/crowd_agents.h"
#include "systems/animation_sample.h"
#include "systems/fk.h"
#include "systems/ik.h"
#include "systems/locomotion.h"
#include "systems/mocap_drive.h"
#include "systems/muscle.h"
#include "systems/job.h"
#include "systems/subdiv.h"
#include "systems/lod.h"
#include "systems/ownership.h"

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

// The same over the tables whose walkers run the whole pipeline this frame (slot_is_light, scene/crowd.h).
template <class System>
void for_each_full_table(Crowd& crowd, System&& system) {
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    if (slot_is_light(static_cast<DetailSlot>(s), crowd.motion.source)) continue;
    SoaTable& t = crowd.world.table(crowd.tables[s]);
    if (t.size() > 0) system(t);
  }
}

// The mesh budget (LodPolicy::mesh_budget): when more walkers qualify for a mesh than the budget allows, the
// nearest keep it and the others become impostors. Ranked by distance, a walker already a mesh as if `hysteresis`
// times nearer; ties by entity index, so the cut is the same whatever order the tables hold their rows in.
void apply_mesh_budget(Crowd& crowd) {
  CrowdLod& lod = crowd.lod;
  lod.over_budget = 0;
  const std::size_t budget = lod.policy.mesh_budget;
  if (budget == 0) return;
  auto& candidates = lod.candidates;
  candidates.clear();
  const float nearer = 1.0f / std::max(lod.policy.hysteresis, 1.0f);
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    const SoaTable& t = crowd.world.table(crowd.tables[s]);
    const bool was_mesh = s < static_cast<std::size_t>(kMaxMeshLevels);
    for (std::size_t b = 0; b < t.size(); ++b)
      if (lod.decided[s][b] < kMaxMeshLevels)
        candidates.push_back({lod.distance[s][b] * (was_mesh ? nearer : 1.0f), static_cast<std::uint32_t>(s),
                              static_cast<std::uint32_t>(b), t.owner(static_cast<std::uint32_t>(b)).index});
  }
  if (candidates.size() <= budget) return;
  const auto nearest_first = [](const CrowdLod::Candidate& a, const CrowdLod::Candidate& b) {
    return a.key != b.key ? a.key < b.key : a.walker < b.walker;
  };
  std::nth_element(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(budget), candidates.end(),
                   nearest_first);
  for (std::size_t i = budget; i < candidates.size(); ++i)
    lod.decided[candidates[i].slot][candidates[i].row] = static_cast<std::uint8_t>(DetailSlot::Impostor);
  lod.over_budget = candidates.size() - budget;
}

// A crowd spread over processes (CrowdLod::ownership): walkers outside this process's slab are culled here, after
// the camera's decision and before the mesh budget, so the budget ranks only the walkers this process draws (it
// bounds one machine's frame, so each process keeps its own).
void apply_ownership(const Crowd& crowd, const SoaTable& t, std::vector<std::uint8_t>& decided) {
  if (!crowd.lod.ownership || t.size() == 0) return;
  OwnershipJob job;
  job.region = &*crowd.lod.ownership;
  job.culled_slot = static_cast<std::uint8_t>(DetailSlot::Culled);
  job.walkers = t.size();
  job.stride = t.stride();
  job.placement = t.f32_base(kWalkerPlacement);
  job.decided = std::span<std::uint8_t>(decided.data(), t.size());
  if (!job.run()) throw std::logic_error("step: the ownership job rejected table " + t.name());
}

// The level-of-detail stage, first in the frame: the table each walker is simulated and skinned from this frame,
// and the moves that put it there. It reads the placement the last frame left (a walker moves ~5 cm a frame, far
// less than its bounding sphere), so the systems after it know which walkers need their whole pipeline.
void lod_stage(Crowd& crowd, FrameProfile& profile) {
  CrowdLod& lod = crowd.lod;
  const DetailLevel level = crowd.skin.level;
  const int levels = crowd.rig().body ? static_cast<int>(crowd.rig().body->levels.size()) : 0;
  const bool impostors = crowd_may_use_impostors(crowd);
  // Culling and tiers need a camera; S levels are drawn whole (their cage pass has no per-walker subset).
  const bool decide = lod.view && (level.is_mesh() || level.is_automatic() || (level.is_impostor() && impostors));
  const DetailSlot fixed_slot = initial_slot(crowd);
  const glm::vec3 root_center = crowd.rig().skeleton.centers.empty() ? glm::vec3(0.0f) : crowd.rig().skeleton.centers[0];
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    SoaTable& t = crowd.world.table(crowd.tables[s]);
    std::vector<std::uint8_t>& decided = lod.decided[s];
    if (decided.size() < t.size()) decided.resize(t.capacity());
    if (lod.distance[s].size() < t.size()) lod.distance[s].resize(t.capacity());
    if (t.size() == 0) continue;
    if (!decide) {
      // No camera yet. Under auto with impostors every walker stays where it is: a walking crowd spawns as
      // impostors, and moving 100,000 of them to level 0 to skin them all once (43 GB) before the first camera
      // arrives is what the tiers are for avoiding. Otherwise the level's table.
      const std::uint8_t to = level.is_automatic() && impostors ? static_cast<std::uint8_t>(s)
                                                                : static_cast<std::uint8_t>(fixed_slot);
      std::fill(decided.begin(), decided.begin() + static_cast<std::ptrdiff_t>(t.size()), to);
      apply_ownership(crowd, t, decided);
      continue;
    }
    // The table a walker is in is its previous decision: hysteresis needs nothing else. Culled (and never seen)
    // walkers have none, so their first decision is the plain one.
    const auto slot = static_cast<DetailSlot>(s);
    const int previous = s < static_cast<std::size_t>(kMaxMeshLevels) ? static_cast<int>(s)
                         : slot == DetailSlot::Impostor             ? kLodImpostor
                                                                    : kLodNoPrevious;
    LodJob job;
    job.view = &*lod.view;
    job.policy = &lod.policy;
    job.body_height = crowd.skin.body_height;
    job.root_center = root_center;
    job.previous_level = previous;
    job.fixed_level = level.is_automatic() ? -1 : level.is_impostor() ? kLodImpostor : level.index();
    job.levels = std::max(levels, 1);
    job.impostors = impostors && level.is_automatic();
    job.culled_slot = static_cast<std::uint8_t>(DetailSlot::Culled);
    job.impostor_slot = static_cast<std::uint8_t>(DetailSlot::Impostor);
    job.walkers = t.size();
    job.stride = t.stride();
    job.placement = t.f32_base(kWalkerPlacement);
    job.root_translation = t.f32_base(kWalkerRootTranslation);
    job.decided = std::span<std::uint8_t>(decided.data(), t.size());
    job.distance = std::span<float>(lod.distance[s].data(), t.size());
    if (!job.run()) throw std::logic_error("step: the level-of-detail job rejected table " + t.name());
    apply_ownership(crowd, t, decided);
  }
  if (decide && level.is_automatic() && impostors) apply_mesh_budget(crowd);
  else lod.over_budget = 0;
  // Apply the moves after every decision, so no walker is decided twice. Handles are stable across moves; rows
  // are not (swap-remove), so the movers are collected first.
  std::vector<std::pair<Entity, DetailSlot>>& moves = lod.moves;
  moves.clear();
  lod.restarted.clear();
  const MotionSource source = crowd.motion.source;
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    const SoaTable& t = crowd.world.table(crowd.tables[s]);
    for (std::size_t b = 0; b < t.size(); ++b) {
      const auto to = static_cast<DetailSlot>(lod.decided[s][b]);
      if (to == static_cast<DetailSlot>(s)) continue;
      const Entity walker = t.owner(static_cast<std::uint32_t>(b));
      moves.emplace_back(walker, to);
      if (slot_is_light(static_cast<DetailSlot>(s), source) && !slot_is_light(to, source))
        lod.restarted.push_back(walker);
    }
  }
  for (const auto& [walker, to] : moves) crowd.world.move(walker, crowd.tables[slot_index(to)]);
  profile.moved = moves.size();
}

// Walkers back from a light table have no feet, pelvis or pose (the impostor table does not hold them; a culled
// walker's are stale): their walk restarts from the phase and path distance the gait clock kept, as a new walker's
// starts, so their first frame in the new tier is a settled pose at the right place.
void restart_walks(Crowd& crowd) {
  const CrowdMotion& m = crowd.motion;
  if (m.source != MotionSource::Walk || !m.locomotion) return;
  for (const Entity walker : crowd.lod.restarted) {
    const EntityLocation at = crowd.world.location(walker);
    SoaTable& t = crowd.world.table(at.table);
    // Rotations a light table does not hold come back as zeros; the joints the walk does not drive rest at
    // identity, as for a new walker.
    if (t.f32(kWalkerLocalRotation, 3)[at.block] == 0.0f)
      for (std::uint32_t j = 0; j < crowd.joint_count(); ++j) t.f32(kWalkerLocalRotation, j * 4 + 3)[at.block] = 1.0f;
    run_or_throw(make_start_walking_job(*m.locomotion, m.paths, t, at.block, m.style, crowd.agents != nullptr),
                 "start_walking");
  }
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
    case Stage::Navigation: return "navigation";
    case Stage::Avoidance: return "avoidance";
  }
  return "?";
}

FrameProfile step(Crowd& crowd, float dt, Profiler& profiler) {
  if (!std::isfinite(dt) || dt < 0.0f) throw std::invalid_argument("step: dt must be finite and >= 0, got " + std::to_string(dt));
  FrameProfile profile;
  const auto start = std::chrono::steady_clock::now();
  const Rig& rig = crowd.rig();
  const CrowdMotion& m = crowd.motion;

  // 1. Level of detail: which table each walker is simulated and skinned from; walkers leaving a light table
  // restart their walk.
  CrowdSkin& skin = crowd.skin;
  {
    StageTimer t(profiler, profile, Stage::Lod);
    lod_stage(crowd, profile);
    restart_walks(crowd);
  }
  // 2-3. Motion: what drives the walkers picks the first systems. A walking crowd's light tables only keep their
  // gait clock (simulation level of detail, scene/crowd.h).
  if (m.source == MotionSource::Walk && m.locomotion) {
    const bool agents = crowd.agents != nullptr;
    if (agents) {
      {
        StageTimer t(profiler, profile, Stage::Navigation);
        run_navigation_stage(crowd, dt);
      }
      StageTimer t(profiler, profile, Stage::Avoidance);
      run_avoidance_stage(crowd, dt);
    }
    {
      StageTimer t(profiler, profile, Stage::Locomotion);
      for_each_table(crowd, [&](SoaTable& t) {
        if (is_light_walker_table(t) || &t == &crowd.table(DetailSlot::Culled))
          run_or_throw(make_gait_advance_job(*m.locomotion, m.paths, t, dt, m.style, agents), "gait_advance");
        else
          run_or_throw(make_locomotion_job(*m.locomotion, m.paths, t, dt, m.style, agents), "locomotion");
      });
    }
    StageTimer t(profiler, profile, Stage::Ik);
    for_each_full_table(crowd, [&](SoaTable& t) { run_or_throw(make_ik_job(rig.skeleton, m.locomotion->limbs, t), "ik"); });
  } else if (m.source == MotionSource::Mocap && m.mocap_rig) {
    {
      StageTimer t(profiler, profile, Stage::Mocap);
      for_each_full_table(crowd, [&](SoaTable& t) { run_or_throw(make_mocap_drive_job(*m.mocap_rig, t, dt), "mocap"); });
    }
    StageTimer t(profiler, profile, Stage::Ik);
    for_each_full_table(crowd, [&](SoaTable& t) { run_or_throw(make_ik_job(rig.skeleton, m.mocap_rig->limbs, t), "ik"); });
  } else {
    StageTimer t(profiler, profile, Stage::Animation);
    for_each_full_table(crowd, [&](SoaTable& t) { run_or_throw(make_animation_job(rig, t, dt), "animation"); });
  }
  // 4. Forward kinematics.
  {
    StageTimer t(profiler, profile, Stage::Fk);
    for_each_full_table(crowd, [&](SoaTable& t) { run_or_throw(make_fk_job(rig.skeleton, t), "fk"); });
  }
  // 5. Muscles.
  if (crowd.muscles_enabled()) {
    StageTimer t(profiler, profile, Stage::Muscle);
    for_each_full_table(crowd, [&](SoaTable& t) { run_or_throw(make_muscle_job(rig.muscles->set, t), "muscle"); });
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
  crowd.lod.impostors = crowd.table(DetailSlot::Impostor).size();
  profile.impostors = crowd.lod.impostors;
  for (std::size_t s = 0; s < kDetailSlots; ++s) profile.walkers_per_slot[s] = crowd.world.table(crowd.tables[s]).size();
  profile.total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return profile;
}

}  // namespace strata
