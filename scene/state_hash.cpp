#include "scene/state_hash.h"

#include <cstring>
#include <vector>

namespace strata {
namespace {

constexpr std::uint64_t kFnvOffset = 1469598103934665603ull;
constexpr std::uint64_t kFnvPrime = 1099511628211ull;

void mix_bytes(std::uint64_t& h, std::uint64_t bits, int bytes) {
  for (int b = 0; b < bytes; ++b) {
    h ^= (bits >> (8 * b)) & 0xffu;
    h *= kFnvPrime;
  }
}

void mix_float(std::uint64_t& h, float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, 4);
  mix_bytes(h, bits, 4);
}

}  // namespace

std::uint64_t walker_state_digest(const Crowd& crowd, Entity walker) {
  std::uint64_t h = kFnvOffset;
  const EntityLocation at = crowd.world.location(walker);
  const SoaTable& t = crowd.world.table(at.table);
  if (is_light_walker_table(t)) {
    // A walker without a pose (an impostor) has only column 0 of the matrices, unused.
    for (std::uint32_t c = 0; c < 5; ++c) mix_float(h, t.f32(kWalkerPlacement, c)[at.block]);
    mix_float(h, t.f32(kWalkerGait, kGaitPhase)[at.block]);
    return h;
  }
  const std::uint32_t width = crowd.joint_count() * kAffineFloats;
  for (const std::uint32_t field : {std::uint32_t(kWalkerWorld), std::uint32_t(kWalkerSkinning)})
    for (std::uint32_t c = 0; c < width; ++c) mix_float(h, t.f32(field, c)[at.block]);
  return h;
}

std::uint64_t combine_walker_digests(std::span<const std::uint64_t> digests) {
  std::uint64_t h = kFnvOffset;
  for (const std::uint64_t d : digests) mix_bytes(h, d, 8);
  return h;
}

std::uint64_t state_hash(const Crowd& crowd) {
  const std::vector<Entity> walkers = crowd.world.entities();
  std::vector<std::uint64_t> digests;
  digests.reserve(walkers.size());
  for (const Entity e : walkers) digests.push_back(walker_state_digest(crowd, e));
  return combine_walker_digests(digests);
}

}  // namespace strata
