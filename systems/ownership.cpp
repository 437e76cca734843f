#include "systems/ownership.h"

#include <cmath>

namespace strata {

bool OwnershipJob::validate() const {
  if (!region || (region->axis != 0 && region->axis != 2)) return false;
  if (std::isnan(region->lo) || std::isnan(region->hi) || region->lo > region->hi) return false;
  if (walkers > 0 && (!placement || stride < walkers)) return false;
  return decided.size() == walkers;
}

bool OwnershipJob::run() const {
  if (!validate()) return false;
  const float* x = placement;
  const float* z = placement + 2 * stride;
  // A walker whose placement is not finite (never placed) is nobody's: NaN compares false both ways.
  for (std::size_t w = 0; w < walkers; ++w)
    if (!region->owns(x[w], z[w])) decided[w] = culled_slot;
  return true;
}

}  // namespace strata
