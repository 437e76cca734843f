#include "scene/crowd_scene.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "motion/track.h"
#include "systems/animation_sample.h"
#include "systems/fk.h"
#include "systems/ik.h"
#include "systems/muscle.h"
#include "rig/muscle_binding.h"

namespace strata {
namespace {

// Uniform [0, 1) from the raw 64-bit engine output, not std::uniform_real_distribution, whose algorithm is
// implementation-defined: the same seed must place the same crowd with any standard library.
float unit_float(std::mt19937_64& rng) { return static_cast<float>(rng() >> 40) * (1.0f / 16777216.0f); }

}  // namespace

CrowdScene::CrowdScene(Rig rig) {
  const auto joints = static_cast<std::uint32_t>(rig.skeleton.joint_count());
  std::string name = rig.name.empty() ? std::string("walkers") : rig.name;
  rig_id_ = rigs_.add(std::move(rig));
  const Rig& r = this->rig();
  const std::uint32_t muscle_points = r.muscles ? r.muscles->set.point_count : 0;
  if (r.muscles && (!r.body || r.muscles->levels.size() != r.body->levels.size()))
    throw std::invalid_argument("CrowdScene: the muscle layer is bound to " + std::to_string(r.muscles->levels.size()) +
                                " body levels, the body has " + std::to_string(r.body ? r.body->levels.size() : 0));
  table_ = world_.add_table(make_walker_table(name, joints, muscle_points));
  try {
    locomotion_ = std::make_unique<const LocomotionRig>(make_locomotion_rig(this->rig().skeleton));
  } catch (const std::exception& e) {
    walk_error_ = e.what();
  }
  // Rest height for projected sizes: the body's, else the skeleton's joint span plus a head's worth.
  if (r.body && !r.body->levels.empty() && !r.body->levels[0].mesh.positions.empty()) {
    float lo = 1e30f, hi = -1e30f;
    for (const glm::vec3& p : r.body->levels[0].mesh.positions) lo = std::min(lo, p.y), hi = std::max(hi, p.y);
    body_height_ = hi - lo;
  } else if (!r.skeleton.centers.empty()) {
    float lo = 1e30f, hi = -1e30f;
    for (const glm::vec3& c : r.skeleton.centers) lo = std::min(lo, c.y), hi = std::max(hi, c.y);
    body_height_ = hi - lo + 0.15f;
  }
  set_body_level(body_level_);
}

const std::vector<LimbChain>& CrowdScene::limbs() const {
  static const std::vector<LimbChain> kNone;
  return locomotion_ ? locomotion_->limbs : kNone;
}

void CrowdScene::spawn_crowd(const CrowdConfig& config) {
  style_ = config.style;
  motion_ = config.motion;
  if (config.motion == MotionSource::Walk)
    spawn_track(config);
  else if (config.motion == MotionSource::Mocap)
    spawn_mocap(config);
  else
    spawn_grid(config);
}

void CrowdScene::set_mocap(RetargetResult capture) {
  if (!locomotion_) throw std::invalid_argument("cannot lock feet: " + walk_error_);
  mocap_ = std::make_unique<const RetargetResult>(std::move(capture));
  mocap_rig_ = std::make_unique<const MocapRig>(make_mocap_rig(rig().skeleton, mocap_->clip, mocap_->contacts));
}

// Mocap walkers start on a grid, facing +Z with a little heading spread so the crowd fans out as it walks,
// out of step (clip phase), each with its own height (uniform scale) and playback rate.
void CrowdScene::spawn_mocap(const CrowdConfig& config) {
  if (!mocap_) throw std::invalid_argument("spawn_crowd: no motion capture set (CrowdScene::set_mocap)");
  std::mt19937_64 rng(config.seed);
  const std::size_t n = config.walkers;
  const std::size_t columns = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  const std::size_t rows = columns == 0 ? 0 : (n + columns - 1) / columns;
  walkers().reserve(walkers().size() + n);
  const float duration = std::max(mocap_->clip.duration, 1e-3f);
  const float rig_height = locomotion_->rig_height;
  for (std::size_t i = 0; i < n; ++i) {
    const float gx = (static_cast<float>(i % columns) - 0.5f * static_cast<float>(columns - 1)) * config.spacing;
    const float gz = (static_cast<float>(i / columns) - 0.5f * static_cast<float>(rows - 1)) * config.spacing;
    const float phase = unit_float(rng) * duration;
    const float rate = 1.0f + (2.0f * unit_float(rng) - 1.0f) * 0.5f * config.rate_jitter;
    const float heading = (2.0f * unit_float(rng) - 1.0f) * 0.5f * config.heading_jitter;
    const float height = config.height_mean + config.height_spread * (2.0f * unit_float(rng) - 1.0f);
    Entity e = spawn(glm::vec3(gx, 0.0f, gz), heading, phase, rate, kRestPose);
    walkers().f32(kWalkerPlacement, 4)[world_.location(e).block] = height / rig_height;
  }
}

Entity CrowdScene::spawn_walker(std::uint32_t path, float distance, float phase, float height, float cadence,
                                float base_speed, float speed_amplitude, float speed_phase) {
  if (!locomotion_) throw std::invalid_argument("cannot walk: " + walk_error_);
  if (path >= paths_.size()) throw std::out_of_range("spawn_walker: no path " + std::to_string(path));
  Entity e = spawn(glm::vec3(0.0f), 0.0f, 0.0f, 1.0f, kRestPose);
  const std::uint32_t block = world_.location(e).block;
  SoaTable& t = walkers();
  const std::pair<std::uint32_t, float> values[] = {
      {kGaitDistance, distance}, {kGaitPhase, phase - std::floor(phase)}, {kGaitCadence, cadence},
      {kGaitCadenceTarget, cadence}, {kGaitHeight, height},
      {kGaitBaseSpeed, base_speed}, {kGaitSpeedAmplitude, speed_amplitude}, {kGaitSpeedPhase, speed_phase}};
  for (const auto& [component, value] : values) t.f32(kWalkerGait, component)[block] = value;
  t.u32(kWalkerPath)[block] = path;
  run_or_throw(make_start_walking_job(*locomotion_, paths_, t, block, style_), "start_walking");
  return e;
}

void CrowdScene::spawn_track(const CrowdConfig& config) {
  if (!locomotion_) throw std::invalid_argument("cannot walk: " + walk_error_);
  std::mt19937_64 rng(config.seed);
  const std::size_t n = config.walkers;
  const int lanes = std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(n)))));
  set_paths(make_stadium_lanes(glm::vec3(0.0f), config.track_straight, config.track_radius, lanes,
                               config.lane_spacing));
  walkers().reserve(walkers().size() + n);
  std::vector<float> lane_speed(static_cast<std::size_t>(lanes)), lane_phase(static_cast<std::size_t>(lanes));
  for (int l = 0; l < lanes; ++l) {
    lane_speed[l] = config.speed_min + (config.speed_max - config.speed_min) * unit_float(rng);
    lane_phase[l] = 6.2831853f * unit_float(rng);
  }
  const std::size_t per_lane = (n + static_cast<std::size_t>(lanes) - 1) / static_cast<std::size_t>(lanes);
  for (std::size_t i = 0; i < n; ++i) {
    const int lane = static_cast<int>(i % static_cast<std::size_t>(lanes));
    const std::size_t slot = i / static_cast<std::size_t>(lanes);
    const float length = paths_[lane].length();
    // Evenly spaced along the lane, jittered by up to a quarter of the gap, lanes staggered.
    const float gap = length / static_cast<float>(per_lane);
    const float distance = std::fmod((static_cast<float>(slot) + 0.25f * unit_float(rng) +
                                      0.37f * static_cast<float>(lane)) * gap, length);
    const float height = config.height_mean + config.height_spread * (2.0f * unit_float(rng) - 1.0f);
    const float phase = unit_float(rng);
    spawn_walker(static_cast<std::uint32_t>(lane), distance, phase, height, 100.0f, lane_speed[lane],
                 config.speed_variation, lane_phase[lane]);
  }
}

Entity CrowdScene::spawn(const glm::vec3& position, float heading, float phase, float rate, int clip) {
  Entity e = world_.create(table_);
  EntityLocation loc = world_.location(e);
  SoaTable& t = walkers();
  const float values[5] = {position.x, position.y, position.z, heading, 1.0f};
  for (std::uint32_t c = 0; c < 5; ++c) t.f32(kWalkerPlacement, c)[loc.block] = values[c];
  t.f32(kWalkerClock, 0)[loc.block] = phase;
  t.f32(kWalkerClock, 1)[loc.block] = rate;
  t.i32(kWalkerClip)[loc.block] = clip;
  // Identity rotations (w = 1) so the walker is in rest pose before its first animation step.
  const std::uint32_t joints = static_cast<std::uint32_t>(rig().skeleton.joint_count());
  for (std::uint32_t j = 0; j < joints; ++j) t.f32(kWalkerLocalRotation, j * 4 + 3)[loc.block] = 1.0f;
  return e;
}

bool CrowdScene::despawn(Entity walker) { return world_.destroy(walker); }

void CrowdScene::spawn_grid(const CrowdConfig& config) {
  motion_ = MotionSource::Clip;
  std::mt19937_64 rng(config.seed);
  const std::size_t n = config.walkers;
  const std::size_t columns = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  const std::size_t rows = columns == 0 ? 0 : (n + columns - 1) / columns;
  walkers().reserve(walkers().size() + n);
  // Phases spread over one cycle of the clip (the longest one when all clips play), so walkers are out of step.
  float duration = 1.0f;
  if (config.clip >= 0 && static_cast<std::size_t>(config.clip) < rig().clips.size()) {
    duration = std::max(rig().clips[config.clip].duration, 1e-3f);
  } else if (config.clip == kAllClips) {
    for (const AnimationClip& c : rig().clips) duration = std::max(duration, c.duration);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const float gx = (static_cast<float>(i % columns) - 0.5f * static_cast<float>(columns - 1)) * config.spacing;
    const float gz = (static_cast<float>(i / columns) - 0.5f * static_cast<float>(rows - 1)) * config.spacing;
    const float phase = unit_float(rng) * duration;
    const float rate = 1.0f + (2.0f * unit_float(rng) - 1.0f) * config.rate_jitter;
    const float heading = (2.0f * unit_float(rng) - 1.0f) * config.heading_jitter;
    spawn(glm::vec3(gx, 0.0f, gz), heading, phase, rate, config.clip);
  }
}

void CrowdScene::simulate(float dt, Profiler& profiler) {
  [[maybe_unused]] Profiler& p = profiler;
  WalkerLanes l = lanes();
  if (motion_ == MotionSource::Walk && locomotion_) {
    {
      STRATA_PROFILE_SCOPE(p, "locomotion");
      run_or_throw(make_locomotion_job(*locomotion_, paths_, walkers(), dt, style_), "locomotion");
    }
    {
      STRATA_PROFILE_SCOPE(p, "ik");
      run_or_throw(make_ik_job(rig().skeleton, locomotion_->limbs, walkers()), "ik");
    }
  } else if (motion_ == MotionSource::Mocap && mocap_rig_) {
    {
      STRATA_PROFILE_SCOPE(p, "mocap");
      run_or_throw(make_mocap_drive_job(*mocap_rig_, walkers(), dt), "mocap");
    }
    {
      STRATA_PROFILE_SCOPE(p, "ik");
      run_or_throw(make_ik_job(rig().skeleton, mocap_rig_->limbs, walkers()), "ik");
    }
  } else {
    STRATA_PROFILE_SCOPE(p, "animation");
    run_or_throw(make_animation_job(rig(), walkers(), dt), "animation");
  }
  {
    STRATA_PROFILE_SCOPE(p, "fk");
    run_or_throw(make_fk_job(rig().skeleton, walkers()), "fk");
  }
  if (muscles_enabled()) {
    STRATA_PROFILE_SCOPE(p, "muscle");
    run_or_throw(make_muscle_job(rig().muscles->set, walkers()), "muscle");
  }
  const int level = body_level();
  lod_counts_ = {};
  if (subdiv_) {
    STRATA_PROFILE_SCOPE(p, "subdiv");  // cage skinning + refinement + normals
    run_or_throw(make_subdiv_job(*subdiv_, walkers(), skinned_, muscles_enabled() ? &cage_muscles_ : nullptr), "subdiv");
    lod_counts_[0] = l.count;
  } else if (level >= 0 && (view_ || level == kAutoBodyLevel)) {
    const bool automatic = level == kAutoBodyLevel;
    const int levels = static_cast<int>(rig().body->levels.size());
    {
      STRATA_PROFILE_SCOPE(p, "lod");
      if (view_) {
        lod_system(*view_, lod_policy_, l, body_height_, automatic ? -1 : level, levels);
      } else {  // automatic without a camera: everybody at the finest level
        for (std::size_t w = 0; w < l.count; ++w) l.at(l.lod, 0)[w] = 0.0f;
      }
      const std::size_t slots = automatic ? level_layouts_.size() : 1;
      level_walkers_.resize(slots);
      for (auto& ids : level_walkers_) ids.clear();
      for (std::size_t w = 0; w < l.count; ++w) {
        const int chosen = static_cast<int>(l.at(l.lod, 0)[w]);
        if (chosen < 0) {
          ++lod_counts_[3];
          continue;
        }
        ++lod_counts_[static_cast<std::size_t>(std::min(chosen, 2))];
        level_walkers_[automatic ? static_cast<std::size_t>(chosen) : 0].push_back(static_cast<std::uint32_t>(w));
      }
    }
    STRATA_PROFILE_SCOPE(p, "skin");
    if (automatic) {
      level_out_.resize(level_layouts_.size());
      for (std::size_t k = 0; k < level_layouts_.size(); ++k)
        run_or_throw(make_skin_job(level_layouts_[k], walkers(), level_out_[k], &level_walkers_[k]), "skin");
    } else {
      run_or_throw(make_skin_job(layout_, walkers(), skinned_, &level_walkers_[0]), "skin");
    }
  } else if (level >= 0) {
    STRATA_PROFILE_SCOPE(p, "skin");
    run_or_throw(make_skin_job(layout_, walkers(), skinned_), "skin");
    lod_counts_[static_cast<std::size_t>(std::min(level, 2))] = l.count;
  } else {
    skinned_ = SkinnedCrowd{};
  }
}

std::vector<CrowdScene::BodyDraw> CrowdScene::body_draws() const {
  std::vector<BodyDraw> draws;
  const int level = body_level();
  if (level < 0) return draws;
  if (level == kAutoBodyLevel) {
    for (std::size_t k = 0; k < level_out_.size() && k < level_layouts_.size(); ++k)
      if (level_out_[k].walkers > 0) draws.push_back({static_cast<int>(k), &level_layouts_[k].triangles, &level_out_[k]});
  } else if (skinned_.walkers > 0) {
    draws.push_back({level, &body_triangles(), &skinned_});
  }
  return draws;
}

void CrowdScene::set_body_level(int level) {
  body_level_ = level;
  rebuild_layout();
}

void CrowdScene::set_muscles_enabled(bool on) {
  muscles_on_ = on;
  rebuild_layout();
}

void CrowdScene::set_muscle_gains(MuscleGains gains) {
  gains_ = std::move(gains);
  const int used = body_level();
  if (used >= 0 && muscles_enabled()) rebuild_muscle_coefficients();
}

void CrowdScene::set_body(std::shared_ptr<const Body> body) {
  const Rig& current = rig();
  if (!current.body || !body || body->levels.size() != current.body->levels.size())
    throw std::invalid_argument("CrowdScene::set_body: the new body must have the current body's levels");
  for (std::size_t k = 0; k < body->levels.size(); ++k)
    if (body->levels[k].mesh.vertex_count() != current.body->levels[k].mesh.vertex_count() ||
        body->levels[k].binding.vertex_count() != body->levels[k].mesh.vertex_count())
      throw std::invalid_argument("CrowdScene::set_body: level " + std::to_string(k) + " changed its vertex count");
  Rig edited = current;
  edited.body = std::move(body);
  rigs_.replace(rig_id_, std::move(edited));
  // The mocap rig points at the skeleton, which now lives in the new rig.
  if (mocap_) mocap_rig_ = std::make_unique<const MocapRig>(make_mocap_rig(rig().skeleton, mocap_->clip, mocap_->contacts));
  rebuild_layout();
}

void CrowdScene::rebuild_layout() {
  const int used = body_level();
  subdiv_ = is_subdiv_level(used) ? body_subdiv_surface(*rig().body, subdiv_depth(used)) : nullptr;
  layout_ = SkinLayout{};
  level_layouts_.clear();
  level_out_.clear();
  cage_muscles_ = MuscleDisplacementList{};
  if (used < 0) return;
  if (used == kAutoBodyLevel) {
    for (std::size_t k = 0; k < rig().body->levels.size(); ++k)
      level_layouts_.push_back(make_skin_layout(rig().body->levels[k], muscles_enabled() ? &rig().muscles->levels[k] : nullptr));
    if (muscles_enabled()) rebuild_muscle_coefficients();
    return;
  }
  if (subdiv_) {
    if (muscles_enabled() && rig().muscles->cage) rebuild_muscle_coefficients();
    return;
  }
  const auto index = static_cast<std::size_t>(used);
  layout_ = make_skin_layout(rig().body->levels[index], muscles_enabled() ? &rig().muscles->levels[index] : nullptr);
  if (muscles_enabled()) rebuild_muscle_coefficients();
}

void CrowdScene::rebuild_muscle_coefficients() {
  const MuscleRig& m = *rig().muscles;
  if (subdiv_) {
    if (m.cage)
      cage_muscles_ = make_muscle_displacement_list(subdiv_->cage_layout, *m.cage, muscle_coefficients(m.set, *m.cage, gains_));
    return;
  }
  const int used = body_level();
  if (used == kAutoBodyLevel) {
    for (std::size_t k = 0; k < level_layouts_.size(); ++k)
      if (level_layouts_[k].has_muscles()) set_muscle_coefficients(level_layouts_[k], muscle_coefficients(m.set, m.levels[k], gains_));
    return;
  }
  if (used < 0 || !layout_.has_muscles()) return;
  const MuscleBinding& binding = m.levels[static_cast<std::size_t>(used)];
  set_muscle_coefficients(layout_, muscle_coefficients(m.set, binding, gains_));
}

int CrowdScene::body_level() const {
  const Body* body = rig().body.get();
  if (!body || body->levels.empty() || body_level_ < 0) return -1;
  if (is_subdiv_level(body_level_)) return body->cage ? body_level_ : 0;
  if (body_level_ == kAutoBodyLevel) return kAutoBodyLevel;
  return std::min(body_level_, static_cast<int>(body->levels.size()) - 1);
}

std::uint64_t CrowdScene::state_hash() const {
  std::uint64_t h = 1469598103934665603ull;
  const SoaTable& t = walkers();
  auto mix = [&](std::span<const float> column) {
    for (float v : column) {
      std::uint32_t bits;
      std::memcpy(&bits, &v, 4);
      for (int b = 0; b < 4; ++b) {
        h ^= (bits >> (8 * b)) & 0xffu;
        h *= 1099511628211ull;
      }
    }
  };
  for (std::uint32_t field : {std::uint32_t(kWalkerWorld), std::uint32_t(kWalkerSkinning)})
    for (std::uint32_t c = 0; c < t.fields()[field].width; ++c) mix(t.f32(field, c));
  return h;
}

}  // namespace strata
