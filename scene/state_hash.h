#pragma once
// The determinism pin: FNV-1a over the bytes of every walker's world and skinning matrices. The order is
// canonical — field by field, component by component, walkers in creation order — so the hash does not depend
// on which tables (levels of detail, culled) the walkers sit in, nor on thread count.
#include <cstdint>

#include "scene/crowd.h"

namespace strata {

std::uint64_t state_hash(const Crowd& crowd);

}  // namespace strata
