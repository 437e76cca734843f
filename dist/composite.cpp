#include "dist/composite.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace strata {

void composite_nearest(std::span<std::uint8_t> acc_pixels, std::span<float> acc_depth,
                       std::span<const std::uint8_t> pixels, std::span<const float> depth) {
  if (acc_pixels.size() != 4 * acc_depth.size() || pixels.size() != acc_pixels.size() || depth.size() != acc_depth.size())
    throw std::invalid_argument("composite_nearest: colour and depth sizes disagree");
  const std::size_t n = acc_depth.size();
  for (std::size_t i = 0; i < n; ++i) {
    const float d = depth[i];
    std::uint8_t* a = &acc_pixels[4 * i];
    const std::uint8_t* p = &pixels[4 * i];
    if (d < acc_depth[i]) {
      acc_depth[i] = d;
      std::memcpy(a, p, 4);
    } else if (d == acc_depth[i] && std::memcmp(a, p, 4) != 0) {
      // A tie between different colours: the same ground or prop with another rank's shadow on it.
      for (int c = 0; c < 4; ++c) a[c] = std::min(a[c], p[c]);
    }
  }
}

std::pair<int, int> band_rows(int height, int pieces, int k) {
  if (height < 0 || pieces < 1 || k < 0 || k >= pieces) throw std::invalid_argument("band_rows: bad arguments");
  const int base = height / pieces, extra = height % pieces;
  const int first = k * base + std::min(k, extra);
  return {first, first + base + (k < extra ? 1 : 0)};
}

}  // namespace strata
