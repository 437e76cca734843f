#pragma once
// Sort-last compositing: the frames that processes rendered of their own walkers (colour + depth, full size)
// folded into one. Per pixel the nearest depth wins; where depths are equal (the ground and props every process
// draws identically, the clear colour) the channels' minimum is kept, which leaves identical pixels as they are
// and keeps every process's shadow on a shared ground (a shadow only darkens). Both rules are commutative and
// associative, so the result does not depend on how many processes there are or in which order their pieces
// arrive: the basis of `mpirun -np K` drawing the frame one process draws (docs/scale-out.md says where it
// cannot).
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>

namespace strata {

// Folds `pixels` (RGBA8, 4 bytes each) and `depth` (one float each, smaller is nearer) into `acc_pixels` and
// `acc_depth`, pixel by pixel. Throws std::invalid_argument when the sizes disagree.
void composite_nearest(std::span<std::uint8_t> acc_pixels, std::span<float> acc_depth,
                       std::span<const std::uint8_t> pixels, std::span<const float> depth);

// The rows [first, last) of an image `height` rows high that piece `k` of `pieces` covers: near-equal bands, the
// first ones one row taller when the division leaves a remainder.
std::pair<int, int> band_rows(int height, int pieces, int k);

}  // namespace strata
