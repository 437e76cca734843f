#pragma once
// The determinism pin. Each walker's digest is FNV-1a over the bytes of its world and skinning matrices (a walker
// without a pose, an impostor, over its placement and gait phase instead); the crowd's hash is FNV-1a over the
// digests, walkers in creation order. So the hash does not depend on which tables (levels of detail, culled) the
// walkers sit in, nor on thread count, and a crowd spread over processes (dist/) combines the digests each
// process computed for its own walkers into the same value.
//
// Walker-major since the crowd was spread over processes; the field-major order before (every walker's first
// matrix float, then every walker's second...) gave the same guarantees but could only be computed by a process
// holding every walker's matrices.
#include <cstdint>
#include <span>

#include "scene/crowd.h"

namespace strata {

std::uint64_t walker_state_digest(const Crowd& crowd, Entity walker);
// FNV-1a over `digests` in order.
std::uint64_t combine_walker_digests(std::span<const std::uint64_t> digests);
std::uint64_t state_hash(const Crowd& crowd);

}  // namespace strata
