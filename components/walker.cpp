#include "components/walker.h"

#include <algorithm>
#include <stdexcept>

namespace strata {

std::unique_ptr<SoaTable> make_walker_table(std::string name, std::uint32_t joint_count,
                                            std::uint32_t muscle_points, bool agents) {
  if (joint_count == 0) throw std::invalid_argument("make_walker_table: a rig needs at least one joint");
  if (muscle_points == 1) throw std::invalid_argument("make_walker_table: an action line has at least 2 points");
  const std::uint32_t p = std::max<std::uint32_t>(muscle_points, 1);
  std::vector<FieldDesc> fields(kWalkerFieldCount);
  fields[kWalkerPlacement] = {"placement", ScalarType::F32, 5, 0.0f};
  fields[kWalkerClock] = {"clock", ScalarType::F32, 2, 0.0f};
  fields[kWalkerClip] = {"clip", ScalarType::I32, 1, 0.0f};
  fields[kWalkerLocalRotation] = {"local_rotation", ScalarType::F32, joint_count * 4, 0.0f};
  fields[kWalkerRootTranslation] = {"root_translation", ScalarType::F32, 3, 0.0f};
  fields[kWalkerWorld] = {"world", ScalarType::F32, joint_count * kAffineFloats, 0.0f};
  fields[kWalkerSkinning] = {"skinning", ScalarType::F32, joint_count * kAffineFloats, 0.0f};
  fields[kWalkerIkGoal] = {"ik_goal", ScalarType::F32, kIkLimbs * kIkGoalFloats, 0.0f};
  fields[kWalkerIkResult] = {"ik_result", ScalarType::F32, kIkLimbs * kIkResultFloats, 0.0f};
  fields[kWalkerIkMode] = {"ik_mode", ScalarType::I32, kIkLimbs, 0.0f};
  fields[kWalkerIkFlags] = {"ik_flags", ScalarType::U32, kIkLimbs, 0.0f};
  fields[kWalkerGait] = {"gait", ScalarType::F32, kGaitFloats, 0.0f};
  fields[kWalkerPath] = {"path", ScalarType::U32, 1, 0.0f};
  fields[kWalkerFootLock] = {"foot_lock", ScalarType::F32, 2 * kLockFloats, -1.0f};
  // Agent fields have their width only in a scenario crowd's tables; elsewhere one unused column each (a field
  // cannot be empty), so a lane walker's impostor row stays as narrow as before agents existed.
  fields[kWalkerAgent] = {"agent", ScalarType::F32, agents ? kAgentFloats : 1u, 0.0f};
  fields[kWalkerAgentState] = {"agent_state", ScalarType::U32, agents ? kAgentInts : 1u, 0.0f};
  fields[kWalkerAgentCorners] = {"agent_corners", ScalarType::F32, agents ? kAgentCorners * 2 + 1 : 1u, 0.0f};
  fields[kWalkerMusclePoint] = {"muscle_point", ScalarType::F32, p * 3, 0.0f};
  fields[kWalkerMuscleFrame] = {"muscle_frame", ScalarType::F32, p * 6, 0.0f};
  fields[kWalkerMuscleLength] = {"muscle_length", ScalarType::F32, p, 0.0f};
  fields[kWalkerMuscleForce] = {"muscle_force", ScalarType::F32, p, 0.0f};
  return std::make_unique<SoaTable>(std::move(name), std::move(fields), 1);
}

std::unique_ptr<SoaTable> make_light_walker_table(std::string name, bool agents) {
  // The full table of a one-joint rig without muscles has width 4 rotations and 12 floats per matrix; narrowed to
  // one column each, which no full table of any rig has (a rig has joints, so rotations are >= 4 wide).
  std::unique_ptr<SoaTable> full = make_walker_table("", 1, 0, agents);
  std::vector<FieldDesc> fields = full->fields();
  for (const std::uint32_t f : {kWalkerLocalRotation, kWalkerWorld, kWalkerSkinning, kWalkerIkGoal, kWalkerIkResult,
                                kWalkerIkMode, kWalkerIkFlags, kWalkerFootLock, kWalkerMusclePoint, kWalkerMuscleFrame,
                                kWalkerMuscleLength, kWalkerMuscleForce})
    fields[f].width = 1;
  return std::make_unique<SoaTable>(std::move(name), std::move(fields), 1);
}

bool is_light_walker_table(const SoaTable& table) {
  return table.fields().size() == kWalkerFieldCount && table.fields()[kWalkerLocalRotation].width == 1;
}

WalkerLanes walker_lanes(SoaTable& table, std::uint32_t joint_count) {
  if (table.fields().size() != kWalkerFieldCount || table.fields()[kWalkerLocalRotation].width != joint_count * 4)
    throw std::invalid_argument("walker_lanes: table '" + table.name() + "' is not a walker table for " +
                                std::to_string(joint_count) + " joints");
  WalkerLanes lanes;
  lanes.count = table.size();
  lanes.stride = table.stride();
  lanes.joints = joint_count;
  const std::uint32_t points = table.fields()[kWalkerMuscleForce].width;
  lanes.muscle_points = points >= 2 ? points : 0;
  if (lanes.count == 0) return lanes;
  lanes.placement = table.f32_base(kWalkerPlacement);
  lanes.clock = table.f32_base(kWalkerClock);
  lanes.local_rotation = table.f32_base(kWalkerLocalRotation);
  lanes.root_translation = table.f32_base(kWalkerRootTranslation);
  lanes.world = table.f32_base(kWalkerWorld);
  lanes.skinning = table.f32_base(kWalkerSkinning);
  lanes.ik_goal = table.f32_base(kWalkerIkGoal);
  lanes.ik_result = table.f32_base(kWalkerIkResult);
  lanes.gait = table.f32_base(kWalkerGait);
  lanes.foot_lock = table.f32_base(kWalkerFootLock);
  lanes.clip = table.i32(kWalkerClip).data();
  lanes.path = table.u32(kWalkerPath).data();
  lanes.ik_mode = table.i32(kWalkerIkMode).data();
  lanes.ik_flags = table.u32(kWalkerIkFlags).data();
  lanes.muscle_point = table.f32_base(kWalkerMusclePoint);
  lanes.muscle_frame = table.f32_base(kWalkerMuscleFrame);
  lanes.muscle_length = table.f32_base(kWalkerMuscleLength);
  lanes.muscle_force = table.f32_base(kWalkerMuscleForce);
  return lanes;
}

}  // namespace strata
