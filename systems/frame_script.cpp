#include "systems/frame_script.h"

#include <cmath>
#include <cstring>
#include <random>

#include "systems/animation_sample.h"
#include "systems/fk.h"

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
  table_ = world_.add_table(make_walker_table(name, joints));
}

Entity CrowdScene::spawn(const glm::vec3& position, float heading, float phase, float rate, int clip) {
  Entity e = world_.create(table_);
  EntityLocation loc = world_.location(e);
  SoaTable& t = walkers();
  const float values[5] = {position.x, position.y, position.z, heading, 1.0f};
  for (std::uint32_t c = 0; c < 5; ++c) t.f32(kWalkerPlacement, c)[loc.block] = values[c];
  t.f32(kWalkerClock, 0)[loc.block] = phase;
  t.f32(kWalkerClock, 1)[loc.block] = rate;
  t.f32(kWalkerClock, 2)[loc.block] = static_cast<float>(clip);
  // Identity rotations (w = 1) so the walker is in rest pose before its first animation step.
  const std::uint32_t joints = static_cast<std::uint32_t>(rig().skeleton.joint_count());
  for (std::uint32_t j = 0; j < joints; ++j) t.f32(kWalkerLocalRotation, j * 4 + 3)[loc.block] = 1.0f;
  return e;
}

bool CrowdScene::despawn(Entity walker) { return world_.destroy(walker); }

void CrowdScene::spawn_grid(const CrowdConfig& config) {
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
  {
    STRATA_PROFILE_SCOPE(p, "animation");
    animation_system(rig(), l, dt);
  }
  {
    STRATA_PROFILE_SCOPE(p, "fk");
    fk_system(rig().skeleton, l);
  }
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
