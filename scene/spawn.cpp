#include "scene/spawn.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include "motion/track.h"
#include "scene/body_settings.h"
#include "systems/animation_sample.h"
#include "systems/job.h"

namespace strata {
namespace {

// Grid cell i of a square-ish grid of n cells `spacing` apart, centred on the origin.
glm::vec3 grid_position(std::size_t i, std::size_t n, float spacing) {
  const std::size_t columns = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  const std::size_t rows = columns == 0 ? 0 : (n + columns - 1) / columns;
  const float gx = (static_cast<float>(i % columns) - 0.5f * static_cast<float>(columns - 1)) * spacing;
  const float gz = (static_cast<float>(i / columns) - 0.5f * static_cast<float>(rows - 1)) * spacing;
  return {gx, 0.0f, gz};
}

void reserve(Crowd& crowd, std::size_t more) {
  SoaTable& t = crowd.table(spawn_slot(crowd));
  t.reserve(t.size() + more);
}

// Clip: phases spread over one cycle of the clip (the longest one when all clips play), so walkers are out of step.
void spawn_grid(Crowd& crowd, const CrowdConfig& config) {
  crowd.motion.source = MotionSource::Clip;
  std::mt19937_64 rng(config.seed);
  const std::size_t n = config.walkers;
  reserve(crowd, n);
  const Rig& rig = crowd.rig();
  float duration = 1.0f;
  if (config.clip >= 0 && static_cast<std::size_t>(config.clip) < rig.clips.size()) {
    duration = std::max(rig.clips[config.clip].duration, 1e-3f);
  } else if (config.clip == kAllClips) {
    for (const AnimationClip& c : rig.clips) duration = std::max(duration, c.duration);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const float phase = unit_float(rng) * duration;
    const float rate = 1.0f + (2.0f * unit_float(rng) - 1.0f) * config.rate_jitter;
    const float heading = (2.0f * unit_float(rng) - 1.0f) * config.heading_jitter;
    spawn_clip_walker(crowd, grid_position(i, n, config.spacing), heading, phase, rate, config.clip);
  }
}

// Mocap walkers start on a grid, facing +Z with a little heading spread so the crowd fans out as it walks,
// out of step (clip phase), each with its own height (uniform scale) and playback rate.
void spawn_mocap(Crowd& crowd, const CrowdConfig& config) {
  const CrowdMotion& m = crowd.motion;
  if (!m.mocap) throw std::invalid_argument("spawn_crowd: no motion capture set (set_mocap)");
  std::mt19937_64 rng(config.seed);
  const std::size_t n = config.walkers;
  reserve(crowd, n);
  const float duration = std::max(m.mocap->clip.duration, 1e-3f);
  const float rig_height = m.locomotion->rig_height;
  for (std::size_t i = 0; i < n; ++i) {
    const float phase = unit_float(rng) * duration;
    const float rate = 1.0f + (2.0f * unit_float(rng) - 1.0f) * 0.5f * config.rate_jitter;
    const float heading = (2.0f * unit_float(rng) - 1.0f) * 0.5f * config.heading_jitter;
    const float height = config.height_mean + config.height_spread * (2.0f * unit_float(rng) - 1.0f);
    const Entity e = spawn_clip_walker(crowd, grid_position(i, n, config.spacing), heading, phase, rate, kRestPose);
    const EntityLocation loc = crowd.world.location(e);
    crowd.world.table(loc.table).f32(kWalkerPlacement, 4)[loc.block] = height / rig_height;
  }
}

// Walking crowds: a stadium track of concentric lanes, a few walkers per lane at the lane's speed schedule.
void spawn_track(Crowd& crowd, const CrowdConfig& config) {
  if (!crowd.motion.locomotion) throw std::invalid_argument("cannot walk: " + crowd.motion.walk_error);
  std::mt19937_64 rng(config.seed);
  const std::size_t n = config.walkers;
  const int lanes = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(n)))));
  set_paths(crowd, make_stadium_lanes(glm::vec3(0.0f), config.track_straight, config.track_radius, lanes,
                                      config.lane_spacing));
  reserve(crowd, n);
  std::vector<float> lane_speed(static_cast<std::size_t>(lanes)), lane_phase(static_cast<std::size_t>(lanes));
  for (int l = 0; l < lanes; ++l) {
    lane_speed[l] = config.speed_min + (config.speed_max - config.speed_min) * unit_float(rng);
    lane_phase[l] = 6.2831853f * unit_float(rng);
  }
  const std::size_t per_lane = (n + static_cast<std::size_t>(lanes) - 1) / static_cast<std::size_t>(lanes);
  for (std::size_t i = 0; i < n; ++i) {
    const int lane = static_cast<int>(i % static_cast<std::size_t>(lanes));
    const std::size_t slot = i / static_cast<std::size_t>(lanes);
    const float length = crowd.motion.paths[lane].length();
    // Evenly spaced along the lane, jittered by up to a quarter of the gap, lanes staggered.
    const float gap = length / static_cast<float>(per_lane);
    const float distance = std::fmod((static_cast<float>(slot) + 0.25f * unit_float(rng) +
                                      0.37f * static_cast<float>(lane)) * gap, length);
    const float height = config.height_mean + config.height_spread * (2.0f * unit_float(rng) - 1.0f);
    const float phase = unit_float(rng);
    // The walker's cadence follows its lane's speed schedule (start_walking derives it), so none is given.
    spawn_walker(crowd, static_cast<std::uint32_t>(lane), distance, phase, height, 0.0f, lane_speed[lane],
                 config.speed_variation, lane_phase[lane]);
  }
}

}  // namespace

void spawn_crowd(Crowd& crowd, const CrowdConfig& config) {
  crowd.motion.style = config.style;
  crowd.motion.source = config.motion;
  if (config.motion == MotionSource::Walk)
    spawn_track(crowd, config);
  else if (config.motion == MotionSource::Mocap)
    spawn_mocap(crowd, config);
  else
    spawn_grid(crowd, config);
}

Entity spawn_clip_walker(Crowd& crowd, const glm::vec3& position, float heading, float phase, float rate, int clip) {
  // Made in a wide table: a walker starting as an impostor (spawn_walker) is set up with its whole walk first.
  const DetailSlot start = spawn_slot(crowd);
  const Entity e = crowd.world.create(crowd.tables[slot_index(start == DetailSlot::Impostor ? DetailSlot::Mesh0 : start)]);
  const EntityLocation loc = crowd.world.location(e);
  SoaTable& t = crowd.world.table(loc.table);
  const float values[5] = {position.x, position.y, position.z, heading, 1.0f};
  for (std::uint32_t c = 0; c < 5; ++c) t.f32(kWalkerPlacement, c)[loc.block] = values[c];
  t.f32(kWalkerClock, 0)[loc.block] = phase;
  t.f32(kWalkerClock, 1)[loc.block] = rate;
  t.i32(kWalkerClip)[loc.block] = clip;
  // Identity rotations (w = 1) so the walker is in rest pose before its first animation step.
  for (std::uint32_t j = 0; j < crowd.joint_count(); ++j) t.f32(kWalkerLocalRotation, j * 4 + 3)[loc.block] = 1.0f;
  return e;
}

Entity spawn_walker(Crowd& crowd, std::uint32_t path, float distance, float phase, float height, float cadence,
                    float base_speed, float speed_amplitude, float speed_phase) {
  const CrowdMotion& m = crowd.motion;
  if (!m.locomotion) throw std::invalid_argument("cannot walk: " + m.walk_error);
  if (path >= m.paths.size()) throw std::out_of_range("spawn_walker: no path " + std::to_string(path));
  const Entity e = spawn_clip_walker(crowd, glm::vec3(0.0f), 0.0f, 0.0f, 1.0f, kRestPose);
  const EntityLocation loc = crowd.world.location(e);
  SoaTable& t = crowd.world.table(loc.table);
  const std::pair<std::uint32_t, float> values[] = {
      {kGaitDistance, distance}, {kGaitPhase, phase - std::floor(phase)}, {kGaitCadence, cadence},
      {kGaitCadenceTarget, cadence}, {kGaitHeight, height},
      {kGaitBaseSpeed, base_speed}, {kGaitSpeedAmplitude, speed_amplitude}, {kGaitSpeedPhase, speed_phase}};
  for (const auto& [component, value] : values) t.f32(kWalkerGait, component)[loc.block] = value;
  t.u32(kWalkerPath)[loc.block] = path;
  run_or_throw(make_start_walking_job(*m.locomotion, m.paths, t, loc.block, m.style), "start_walking");
  const DetailSlot start = spawn_slot(crowd);
  if (start == DetailSlot::Impostor) crowd.world.move(e, crowd.tables[slot_index(start)]);
  return e;
}

bool despawn(Crowd& crowd, Entity walker) { return crowd.world.destroy(walker); }

void set_paths(Crowd& crowd, std::vector<CardinalSpline> paths) { crowd.motion.paths = std::move(paths); }

void set_mocap(Crowd& crowd, RetargetResult capture) {
  CrowdMotion& m = crowd.motion;
  if (!m.locomotion) throw std::invalid_argument("cannot lock feet: " + m.walk_error);
  m.mocap = std::make_unique<const RetargetResult>(std::move(capture));
  m.mocap_rig = std::make_unique<const MocapRig>(make_mocap_rig(crowd.rig().skeleton, m.mocap->clip, m.mocap->contacts));
}

}  // namespace strata
