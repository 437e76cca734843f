#include "scene/state_hash.h"

#include <cstring>
#include <vector>

namespace strata {

std::uint64_t state_hash(const Crowd& crowd) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](float v) {
    std::uint32_t bits;
    std::memcpy(&bits, &v, 4);
    for (int b = 0; b < 4; ++b) {
      h ^= (bits >> (8 * b)) & 0xffu;
      h *= 1099511628211ull;
    }
  };
  const std::vector<Entity> walkers = crowd.world.entities();
  std::vector<EntityLocation> where;
  where.reserve(walkers.size());
  for (const Entity e : walkers) where.push_back(crowd.world.location(e));
  const std::uint32_t width = crowd.joint_count() * kAffineFloats;
  for (const std::uint32_t field : {std::uint32_t(kWalkerWorld), std::uint32_t(kWalkerSkinning)})
    for (std::uint32_t c = 0; c < width; ++c)
      for (const EntityLocation& at : where) {
        const SoaTable& t = crowd.world.table(at.table);
        // A walker without a pose (an impostor) has only its column 0 of these, unused; its placement and
        // gait phase are hashed below instead.
        if (!is_light_walker_table(t)) mix(t.f32(field, c)[at.block]);
      }
  for (const EntityLocation& at : where) {
    const SoaTable& t = crowd.world.table(at.table);
    if (!is_light_walker_table(t)) continue;
    for (std::uint32_t c = 0; c < 5; ++c) mix(t.f32(kWalkerPlacement, c)[at.block]);
    mix(t.f32(kWalkerGait, kGaitPhase)[at.block]);
  }
  return h;
}

}  // namespace strata
