#pragma once
// Crowd: the data of one crowd of walkers of one rig, and nothing else. The logic that changes it lives beside it,
// one responsibility per file:
//
//   scene/spawn.h          putting walkers in (grid, stadium track, motion capture) and taking them out
//   scene/body_settings.h  what bodies are drawn with: detail level, muscle layer and gains, edited weights
//   scene/step.h           step(): one frame of the fixed-order system script, with its FrameProfile
//   scene/state_hash.h     the determinism pin
//   render/render_frame.h  render_frame(): drawing the last step and giving the camera to the next one
//
// Where a walker's state is: every walker is a row (entity) of one of the walker tables below, one table per
// DetailSlot. The slot is the walker's detail state — which mesh level it is skinned at this frame, refined
// from the cage, outside the camera (culled), or not skinned at all — so the skin pass for level k is a plain loop
// over table k, and a walker whose level changes is moved between tables (World::move) by the level-of-detail
// stage, which keeps hysteresis by reading the table a walker is in. No per-walker flag is tested in a hot loop.
//
// The Impostor table is narrower than the others: only the fields an impostor reads or the gait clock writes
// (placement, clock, gait, path, root translation) have their full width, the rest one unused column, so a far
// walker costs about 270 bytes instead of a full walker's kilobytes (make_light_walker_table). World::move copies
// only fields of equal width, so a walker leaving it gets a fresh pose, and step() restarts its walk from its
// gait phase and path position before anything reads the pose (StartWalkingJob).
//
// Skinned vertices are per-slot component storage: `skinned[slot]` holds block b's deformed body for row b of
// that slot's table, sized by that table's walkers (grown, never shrunk), so memory follows the walkers drawn at
// each level rather than the crowd.
//
// Shared immutable rig data (skeleton, body levels and bindings, muscle set) is stored once in `rigs`; per-rig
// derived resources that the systems read (locomotion limbs, the mocap rig, skin layouts, the refined cage) are
// built once by the functions above and stored here, not per walker.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "components/detail_level.h"
#include "components/impostor_atlas.h"
#include "components/rig.h"
#include "components/skin_layout.h"
#include "components/walker.h"
#include "ecs/world.h"
#include "motion/cardinal_spline.h"
#include "motion/retarget.h"
#include "systems/locomotion.h"
#include "systems/lod.h"
#include "systems/mocap_drive.h"
#include "systems/ownership.h"
#include "systems/skin.h"
#include "systems/skin_kernel.h"

namespace strata {

struct SubdivSurface;
struct CrowdAgents;

// What drives a crowd's walkers, which picks the frame's first systems (scene/step.h).
enum class MotionSource { Walk, Clip, Mocap };

// The walker tables: a walker sits in exactly one.
enum class DetailSlot : std::uint8_t {
  Mesh0,    // skinned at mesh level 0 this frame
  Mesh1,    // mesh level 1
  Mesh2,    // mesh level 2
  Refined,  // the cage skinned and refined (S1..S3)
  Culled,   // outside the camera: simulated, not skinned, not drawn
  NoBody,   // DetailLevel::none(), or a rig without a body: simulated, drawn as a skeleton
  Impostor, // far away: drawn as one quad from the rig's impostor atlas; only the gait clock and the path run
};
inline constexpr std::size_t kDetailSlots = 7;
inline constexpr std::size_t slot_index(DetailSlot s) { return static_cast<std::size_t>(s); }
inline constexpr DetailSlot mesh_slot(int level) { return static_cast<DetailSlot>(level); }
static_assert(kMaxMeshLevels == 3, "one Mesh slot per mesh level");
const char* slot_name(DetailSlot slot);
// Tables whose walkers run the whole pipeline (locomotion or their clip, IK, FK, muscles) this frame. A walking
// crowd's impostors and culled walkers only advance their gait clock along their path (simulation level of
// detail): nothing they would compute is shown. Clip and capture walkers are never impostors (their motion is
// not the baked walk) and keep their whole pipeline when culled, since a capture's foot locks carry state.
bool slot_is_light(DetailSlot slot, MotionSource source);

// How walkers move: the motion source and what it needs (per rig, built once, read by the systems).
struct CrowdMotion {
  MotionSource source = MotionSource::Clip;
  std::unique_ptr<const LocomotionRig> locomotion;  // null when the rig cannot walk
  std::string walk_error;                           // why it cannot, when it cannot
  std::vector<CardinalSpline> paths;                // paths walking walkers follow (their integer path column)
  GaitStyle style;
  std::unique_ptr<const RetargetResult> mocap;  // owns the clip and contacts mocap_rig points at
  std::unique_ptr<const MocapRig> mocap_rig;
};

// What bodies are skinned with (scene/body_settings.h keeps it consistent with the rig).
struct CrowdSkin {
  DetailLevel requested;  // what was asked for (set_detail_level)
  DetailLevel level = DetailLevel::none();  // what is used: requested, clamped to what the rig's body has
  bool muscles_on = true;
  // How joints are blended (set_skinning_mode); at CentresOfRotation the layouts carry the body's centres.
  SkinningMode mode = SkinningMode::Linear;
  MuscleGains gains;
  // Per mesh level in use, its vertex grouping (the skin kernel's input) with this crowd's muscle coefficients;
  // empty for the levels not in use.
  std::array<SkinLayout, kMaxMeshLevels> layouts;
  std::shared_ptr<const SubdivSurface> subdiv;  // at S levels (owned by the rig's Body; shared)
  MuscleDisplacementList cage_muscles;          // S levels: the cage's muscle displacement, this crowd's gains
  float body_height = 1.75f;                    // rest height of the rig's body (m), for projected sizes
};

// Level of detail: the camera the last render_frame() handed over, and the policy.
struct CrowdLod {
  std::optional<LodView> view;  // none: no culling, every walker at the requested (or finest) level
  LodPolicy policy;
  // Walkers skinned at levels 0, 1, 2 (S levels count as 0) by the last step, and walkers culled.
  std::array<std::size_t, 4> counts{};
  std::size_t impostors = 0;    // walkers drawn as impostors by the last step
  std::size_t over_budget = 0;  // of those, walkers tall enough for a mesh that the mesh budget turned away
  // Scratch of the level-of-detail stage, per table: each row's slot for the next skin pass. Grown, never shrunk.
  std::array<std::vector<std::uint8_t>, kDetailSlots> decided;
  std::vector<std::pair<Entity, DetailSlot>> moves;  // scratch: the walkers that change tables this frame
  // Scratch of the mesh budget, per table: each row's camera distance; and the candidates for a mesh.
  std::array<std::vector<float>, kDetailSlots> distance;
  struct Candidate {
    float key;
    std::uint32_t slot, row;
    std::uint32_t walker;  // entity index, the tie-break that makes the cut independent of table order
  };
  std::vector<Candidate> candidates;
  std::vector<Entity> restarted;  // scratch: walkers that left a light table this frame (their walk restarts)
  // One crowd spread over several processes (dist/): the slab of ground whose walkers this process animates,
  // skins and draws; a held walker outside it (one nobody owns) is culled (systems/ownership.h). None: every
  // walker is this process's.
  std::optional<OwnershipRegion> ownership;
};

struct Crowd {
  // Makes the tables for `rig` and the per-rig resources; throws std::invalid_argument when the rig's muscle
  // layer does not match its body.
  explicit Crowd(Rig rig);
  ~Crowd();
  // Gives the agent fields their width in every table (a scenario crowd, scene/crowd_agents.h); the crowd must
  // have no walker yet. Throws std::logic_error otherwise.
  void widen_for_agents();
  Crowd(const Crowd&) = delete;
  Crowd& operator=(const Crowd&) = delete;

  World world;
  std::array<std::uint32_t, kDetailSlots> tables{};  // walker table id per DetailSlot
  // One crowd spread over several processes (dist/): the walkers another process owns. Not one of `tables`, so no
  // stage reads it: this process keeps only their handles (a narrow row, as the impostors'), and a walker that
  // becomes this process's arrives with its whole row from its old owner (dist/migration.h). Empty otherwise.
  std::uint32_t remote_table = 0;
  bool is_remote(Entity walker) const { return world.location(walker).table == remote_table; }
  RigLibrary rigs;
  RigId rig_id = 0;
  CrowdMotion motion;
  CrowdSkin skin;
  CrowdLod lod;
  std::array<SkinnedCrowd, kDetailSlots> skinned;  // per slot; Culled, NoBody and Impostor stay empty
  // The rig's impostor atlas for this crowd's walk, once the renderer has baked or loaded it
  // (render/impostor_bake.h ensure_impostor_atlas); dropped when the body or its muscle layer is switched. Baked
  // with the default muscle gains: a gain edit shows on meshes, not on impostors.
  std::shared_ptr<const ImpostorAtlas> impostor_atlas;
  // A scenario crowd's steered agents (scene/crowd_agents.h): null for the lane walk, clips and capture. When set,
  // the walk follows each walker's agent instead of a path.
  std::unique_ptr<CrowdAgents> agents;

  const Rig& rig() const { return rigs.get(rig_id); }
  std::uint32_t joint_count() const { return static_cast<std::uint32_t>(rig().skeleton.joint_count()); }
  SoaTable& table(DetailSlot slot) { return world.table(tables[slot_index(slot)]); }
  const SoaTable& table(DetailSlot slot) const { return world.table(tables[slot_index(slot)]); }
  std::size_t walker_count() const { return world.alive_count(); }
  // The slot a live walker is in.
  DetailSlot slot_of(Entity walker) const;
  // Kernel view of one table (valid until that table grows or shrinks).
  WalkerLanes lanes(DetailSlot slot) { return walker_lanes(table(slot), joint_count()); }
  // Kernel view of the one table holding every walker: for tests and tools that read walkers in spawn order.
  // Throws std::logic_error when the walkers are spread over several tables (a camera culls or levels them).
  WalkerLanes lanes();
  // Limb chains of the walk, empty when the rig cannot walk.
  const std::vector<LimbChain>& limbs() const;
  bool has_muscles() const { return rig().muscles != nullptr && rig().muscles->set.point_count > 0; }
  bool muscles_enabled() const { return skin.muscles_on && has_muscles(); }

 private:
  void make_tables(bool agent_fields);
};

}  // namespace strata
