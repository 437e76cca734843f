#pragma once
// Putting walkers into a Crowd (scene/crowd.h) and taking them out. Deterministic for a seed: the same seed
// places the same crowd with any standard library and any thread count.
//
// A new walker starts in the table of the crowd's current detail level (the NoBody table when nothing is
// skinned); the level-of-detail stage of its first step() moves it where the camera puts it.
#include <cstdint>
#include <random>
#include <vector>

#include <glm/vec3.hpp>

#include "scene/crowd.h"

namespace strata {

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

// Spawns `config.walkers` walkers with seeded variety and sets the crowd's motion source. Clip: on a square grid
// centred on the origin, facing +Z (animation phase, playback rate, heading). Walk: spread over the lanes of a
// stadium track (height, lane speed, phase, distance along the lane). Mocap: on a grid, out of step.
void spawn_crowd(Crowd& crowd, const CrowdConfig& config);
// Uniform [0, 1) from the raw 64-bit engine output (24 bits), not std::uniform_real_distribution, whose algorithm
// is implementation-defined: the same seed must place the same crowd with any standard library.
inline float unit_float(std::mt19937_64& rng) { return static_cast<float>(rng() >> 40) * (1.0f / 16777216.0f); }
// A clip-driven walker at `position`, facing `heading` (rad about +Y), at clip time `phase`, playing `clip`.
Entity spawn_clip_walker(Crowd& crowd, const glm::vec3& position, float heading, float phase, float rate, int clip);
// A walking walker on `crowd.motion.paths[path]`: `distance` along it, gait `phase`, body `height` (m), and either
// a constant cadence target (base_speed <= 0; `cadence` steps/min) or a speed schedule (then the walker derives
// its cadence from the speed and `cadence` is not used).
Entity spawn_walker(Crowd& crowd, std::uint32_t path, float distance, float phase, float height, float cadence,
                    float base_speed, float speed_amplitude, float speed_phase);
// Removes a walker; false (and nothing changes) for a dead or stale handle.
bool despawn(Crowd& crowd, Entity walker);

// Paths walkers follow; replacing them keeps walkers' path indices.
void set_paths(Crowd& crowd, std::vector<CardinalSpline> paths);
// Motion capture retargeted onto the crowd's rig (motion/retarget.h); required before spawning with Mocap.
// Throws std::invalid_argument when the rig cannot lock feet (it has no legs to walk with).
void set_mocap(Crowd& crowd, RetargetResult capture);

}  // namespace strata
