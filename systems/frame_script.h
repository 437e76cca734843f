#pragma once
// The frame script: a crowd of walkers of one rig and the fixed order of systems that advance it, each inside a
// profiler scope. `strata crowd`, `strata view` and the tests drive the same script; the renderer runs after it.
//
//   1. animation  clock + keyframed clip -> local rotations, root translation   (systems/animation_sample.h)
//   2. fk         local rotations -> world matrices F(j), skinning F(j)A(j)^-1  (systems/fk.h)
//
// Later issues insert locomotion and IK before FK, muscle after it, then skinning.
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

#include "components/rig.h"
#include "components/walker.h"
#include "ecs/world.h"
#include "profiling/profiler.h"

namespace strata {

struct CrowdConfig {
  std::size_t walkers = 25;
  float spacing = 1.25f;     // metres between grid neighbours
  std::uint64_t seed = 1;    // per-walker phase, rate and heading variation
  int clip = -2;             // clip each walker plays: an index, kAllClips (-2) or kRestPose (-1)
  float rate_jitter = 0.08f; // playback rate drawn in [1 - j, 1 + j]
  float heading_jitter = 0.35f;  // radians either side of facing +Z
};

class CrowdScene {
 public:
  explicit CrowdScene(Rig rig);

  // Places `config.walkers` walkers on a square grid centred on the origin, facing +Z with a little seeded
  // variety (animation phase, playback rate, heading). Deterministic for a given seed.
  void spawn_grid(const CrowdConfig& config);
  Entity spawn(const glm::vec3& position, float heading, float phase, float rate, int clip);
  bool despawn(Entity walker);

  // Runs systems 1..2 for one frame of `dt` seconds.
  void simulate(float dt, Profiler& profiler);

  const Rig& rig() const { return rigs_.get(rig_id_); }
  World& world() { return world_; }
  const World& world() const { return world_; }
  SoaTable& walkers() { return world_.table(table_); }
  const SoaTable& walkers() const { return world_.table(table_); }
  std::size_t walker_count() const { return walkers().size(); }
  WalkerLanes lanes() { return walker_lanes(walkers(), static_cast<std::uint32_t>(rig().skeleton.joint_count())); }

  // Clip selector walker `block` plays (a clip index, kAllClips or kRestPose).
  int clip_of(std::size_t block) const { return static_cast<int>(walkers().f32(kWalkerClock, 2)[block]); }

  // FNV-1a over the bytes of every walker's world and skinning matrices, in walker order: the determinism pin.
  std::uint64_t state_hash() const;

 private:
  RigLibrary rigs_;
  RigId rig_id_ = 0;
  World world_;
  std::uint32_t table_ = 0;
};

}  // namespace strata
