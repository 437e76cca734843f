#pragma once
// The frame script: a crowd of walkers of one rig and the fixed order of systems that advance it, each inside a
// profiler scope. `strata crowd`, `strata view` and the tests drive the same script; the renderer runs after it.
//
// A scene's walkers are driven one of two ways (its MotionSource), which picks the first systems:
//   walk:  1. locomotion  path, cadence, footprints -> placement, pelvis, IK goals    (systems/locomotion.h)
//          2. ik          goals -> arm and leg joint rotations                        (systems/ik.h)
//   clip:  1. animation   clock + keyframed clip -> local rotations, root translation (systems/animation_sample.h)
//   mocap: 1. mocap_drive retargeted capture -> rotations, root motion, foot-lock goals (systems/mocap_drive.h)
//          2. ik          goals -> locked feet
//   then   3. fk          local rotations -> world matrices F(j), skinning F(j)A(j)^-1 (systems/fk.h)
//          4. muscle      skinning matrices -> action-line control points, force factors, when the rig has
//                         a muscle layer and it is on (systems/muscle.h)
//          5. skin        rig body level (+ muscle displacement) -> deformed world-space vertices, when the rig
//                         has a body (systems/skin.h)
//             or subdiv   at levels S1..S3: skin (+ muscle-displace) the cage, refine it (systems/subdiv.h)
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include <memory>
#include <string>

#include "components/rig.h"
#include "components/walker.h"
#include "ecs/world.h"
#include "motion/cardinal_spline.h"
#include "profiling/profiler.h"
#include "motion/retarget.h"
#include "systems/locomotion.h"
#include "systems/lod.h"
#include "systems/mocap_drive.h"
#include "systems/skin.h"
#include "systems/subdiv.h"

namespace strata {

enum class MotionSource { Walk, Clip, Mocap };

struct CrowdConfig {
  MotionSource motion = MotionSource::Walk;
  std::size_t walkers = 25;
  float spacing = 1.25f;     // metres between grid neighbours
  std::uint64_t seed = 1;    // per-walker phase, rate and heading variation
  int clip = -2;             // clip each walker plays: an index, kAllClips (-2) or kRestPose (-1)
  float rate_jitter = 0.08f; // playback rate drawn in [1 - j, 1 + j]
  float heading_jitter = 0.35f;  // radians either side of facing +Z
  // Walking crowds: a stadium track of concentric lanes, a few walkers per lane at the lane's speed schedule
  // (each walker derives its own cadence from the speed and its height, so lanes never collide).
  float height_mean = 1.72f, height_spread = 0.09f;  // body heights: mean +- spread (uniform), metres
  float speed_min = 1.0f, speed_max = 1.4f;          // lane base speeds, m/s
  float speed_variation = 0.1f;                      // relative amplitude of each lane's speed schedule
  float track_straight = 5.0f, track_radius = 2.5f, lane_spacing = 0.9f;
  GaitStyle style;
};

class CrowdScene {
 public:
  explicit CrowdScene(Rig rig);

  // Spawns `config.walkers` walkers with seeded variety, deterministic for a given seed. Clip: on a square grid
  // centred on the origin, facing +Z (animation phase, playback rate, heading). Walk: spread over the lanes of
  // a stadium track (height, lane speed, phase, distance along the lane). Sets the scene's motion source.
  void spawn_crowd(const CrowdConfig& config);
  // A clip-driven walker.
  Entity spawn(const glm::vec3& position, float heading, float phase, float rate, int clip);
  // A walking walker on `paths()[path]`: `distance` along it, gait `phase`, body `height` (m), and either a
  // constant cadence target (base_speed <= 0) or a speed schedule.
  Entity spawn_walker(std::uint32_t path, float distance, float phase, float height, float cadence, float base_speed,
                      float speed_amplitude, float speed_phase);
  bool despawn(Entity walker);

  // Paths walkers follow (shared scene data). Replacing them keeps walkers' path indices.
  void set_paths(std::vector<CardinalSpline> paths) { paths_ = std::move(paths); }
  const std::vector<CardinalSpline>& paths() const { return paths_; }
  // Motion capture retargeted onto this rig (motion/retarget.h); required before spawning with Mocap.
  void set_mocap(RetargetResult capture);
  const RetargetResult* mocap() const { return mocap_.get(); }
  // Why this rig cannot walk (missing limb joints), or empty when it can.
  const std::string& walk_unavailable() const { return walk_error_; }
  const LocomotionRig* locomotion_rig() const { return locomotion_.get(); }
  const std::vector<LimbChain>& limbs() const;
  MotionSource motion() const { return motion_; }
  void set_motion(MotionSource motion) { motion_ = motion; }
  GaitStyle& style() { return style_; }

  // Body level the skin system deforms (clamped to the rig's levels); -1 turns skinning off; S1..S3
  // (subdiv_level(1..3), components/body.h) draw the cage refined 1..3 times, and fall back to level 0 when the
  // rig's body has no cage. Switching at run time is cheap: a subdivided surface is built once per rig.
  void set_body_level(int level);
  int body_level() const;
  // Swaps the rig's body for one with the same meshes and new weights (the binding editor's edits): the skin
  // layouts are rebuilt, the muscle binding (which depends on rest positions only) is kept. Throws
  // std::invalid_argument when a level's vertex count differs or the scene has no body. The rig is replaced by an
  // edited copy (rigs are immutable and may be shared), so references into rig() taken before the call dangle.
  void set_body(std::shared_ptr<const Body> body);
  // The vertex grouping of the current mesh level (empty at S levels: then the cage's is subdiv()->cage_layout);
  // skinned() is in its order (its triangles renumbered to match).
  const SkinLayout& skin_layout() const { return layout_; }
  // Muscle layer: on by default when the rig has one. Off skips the muscle system and skins without
  // displacement (the layout is rebuilt without muscle groups). Gains scale every muscle's forces at run time
  // (the paper's users edited force values); only vertices bound to a changed muscle move.
  bool has_muscles() const { return rig().muscles != nullptr && rig().muscles->set.point_count > 0; }
  void set_muscles_enabled(bool on);
  bool muscles_enabled() const { return muscles_on_ && has_muscles(); }
  void set_muscle_gains(MuscleGains gains);
  const MuscleGains& muscle_gains() const { return gains_; }

  // Level of detail (systems/lod.h). With a view set, walkers outside it are culled (neither skinned nor drawn);
  // at kAutoBodyLevel each visible walker also gets a mesh level from its projected height, with hysteresis.
  // Without a view every walker is skinned (at level 0 under the automatic policy).
  void set_view(const LodView& view) { view_ = view; }
  void clear_view() { view_.reset(); }
  LodPolicy& lod_policy() { return lod_policy_; }
  // Walkers skinned at levels 0, 1, 2 by the last simulate(), and walkers culled.
  std::array<std::size_t, 4> lod_counts() const { return lod_counts_; }
  // What to draw after simulate(): per level in use, its triangles (in its SkinnedCrowd's vertex order) and
  // the skinned walkers (blocks; walker_ids name them when not all walkers are there).
  struct BodyDraw {
    int level = 0;
    const std::vector<std::uint32_t>* triangles = nullptr;
    const SkinnedCrowd* skinned = nullptr;
  };
  std::vector<BodyDraw> body_draws() const;

  // The refined cage drawn at S levels, else null.
  const SubdivSurface* subdiv() const { return subdiv_.get(); }
  // The triangles to draw skinned() with: the level's (layout numbering) or the refined cage's.
  const std::vector<std::uint32_t>& body_triangles() const { return subdiv_ ? subdiv_->triangles : layout_.triangles; }
  // Deformed bodies of the last simulate(), empty when the rig has no body or skinning is off.
  const SkinnedCrowd& skinned() const { return skinned_; }

  // Runs the frame script (see above) for one frame of `dt` seconds.
  void simulate(float dt, Profiler& profiler);

  const Rig& rig() const { return rigs_.get(rig_id_); }
  World& world() { return world_; }
  const World& world() const { return world_; }
  SoaTable& walkers() { return world_.table(table_); }
  const SoaTable& walkers() const { return world_.table(table_); }
  std::size_t walker_count() const { return walkers().size(); }
  WalkerLanes lanes() { return walker_lanes(walkers(), static_cast<std::uint32_t>(rig().skeleton.joint_count())); }

  // Clip selector walker `block` plays (a clip index, kAllClips or kRestPose).
  int clip_of(std::size_t block) const { return walkers().i32(kWalkerClip)[block]; }

  // FNV-1a over the bytes of every walker's world and skinning matrices, in walker order: the determinism pin.
  std::uint64_t state_hash() const;

 private:
  void spawn_grid(const CrowdConfig& config);
  void spawn_track(const CrowdConfig& config);
  void spawn_mocap(const CrowdConfig& config);
  void rebuild_layout();
  void rebuild_muscle_coefficients();

  RigLibrary rigs_;
  RigId rig_id_ = 0;
  World world_;
  std::uint32_t table_ = 0;
  MotionSource motion_ = MotionSource::Clip;
  std::unique_ptr<const LocomotionRig> locomotion_;  // null when the rig cannot walk
  std::string walk_error_;
  std::vector<CardinalSpline> paths_;
  GaitStyle style_;
  std::unique_ptr<const RetargetResult> mocap_;  // owns the clip and contacts mocap_rig_ points at
  std::unique_ptr<const MocapRig> mocap_rig_;
  int body_level_ = 0;
  bool muscles_on_ = true;
  MuscleGains gains_;
  SkinLayout layout_;
  std::shared_ptr<const SubdivSurface> subdiv_;  // set at S levels (owned by the rig's Body; shared)
  MuscleDisplacementList cage_muscles_;           // S levels: the cage's muscle displacement, this scene's gains
  SkinnedCrowd skinned_;
  std::optional<LodView> view_;
  LodPolicy lod_policy_;
  float body_height_ = 1.75f;                   // rest height of the rig's body (m), for projected sizes
  std::vector<SkinLayout> level_layouts_;       // kAutoBodyLevel: every mesh level's layout
  std::vector<SkinnedCrowd> level_out_;         // kAutoBodyLevel: the walkers skinned at each level
  std::vector<std::vector<std::uint32_t>> level_walkers_;  // walkers per level this frame (ascending)
  std::array<std::size_t, 4> lod_counts_{};
};

}  // namespace strata
