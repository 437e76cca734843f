#pragma once
// Sort-last compositing: the frames that processes rendered of their own walkers (colour + depth, full size)
// folded into one. Per pixel the nearest depth wins; where depths are equal (the ground and props every process
// draws identically, the clear colour) the channels' minimum is kept, which leaves identical pixels as they are
// and keeps every process's shadow on a shared ground (a shadow only darkens). Both rules are commutative and
// associative, so the result does not depend on how many processes there are or in which order their pieces
// arrive: the basis of `mpirun -np K` drawing the frame one process draws (docs/scale-out.md says where it
// cannot).
//
// Footprints: outside the pixels its own walkers and their shadows can touch (render/crowd_renderer.h
// last_footprint), a process's frame is the shared scene alone (sky, ground, props), which every process draws
// bit for bit the same; folding such a pixel into the same pixel of another frame leaves that one as it was.
// So a band's owner starts from its own frame and folds in, from each other process, only the band's rows and
// columns inside that process's footprint: the same image for far fewer bytes (IceT's bounding-box culling, in
// the same spirit).
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace strata {

// Folds `pixels` (RGBA8, 4 bytes each) and `depth` (one float each, smaller is nearer) into `acc_pixels` and
// `acc_depth`, pixel by pixel. Throws std::invalid_argument when the sizes disagree.
void composite_nearest(std::span<std::uint8_t> acc_pixels, std::span<float> acc_depth,
                       std::span<const std::uint8_t> pixels, std::span<const float> depth);

// The rows [first, last) of an image `height` rows high that piece `k` of `pieces` covers: near-equal bands, the
// first ones one row taller when the division leaves a remainder.
std::pair<int, int> band_rows(int height, int pieces, int k);

// Pixels [x0, x1) x [y0, y1) of an image, rows top to bottom. Empty when x0 >= x1 or y0 >= y1.
struct ImageRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
  std::size_t area() const {
    return empty() ? 0 : static_cast<std::size_t>(x1 - x0) * static_cast<std::size_t>(y1 - y0);
  }
  bool operator==(const ImageRect&) const = default;
};

// `r` clipped to a width x height image; every empty rectangle becomes {0, 0, 0, 0}.
ImageRect clip_rect(ImageRect r, int width, int height);

// The part of `footprint` (already clipped) in band `k` of `pieces` (band_rows) of an image `height` rows high.
ImageRect band_piece(ImageRect footprint, int height, int pieces, int k);

// Appends the pixels of `piece` of a frame `width` pixels wide to `colour` (4 bytes a pixel) and `depth`, row by
// row.
void pack_piece(std::span<const std::uint8_t> pixels, std::span<const float> depth, int width, ImageRect piece,
                std::vector<std::uint8_t>& colour_out, std::vector<float>& depth_out);

// Folds a packed `piece` (pack_piece's rows) into a band that starts at image row `band_first_row` and is `width`
// pixels wide. Throws std::invalid_argument when the rows or the piece do not fit the band.
void fold_piece(std::span<std::uint8_t> band_pixels, std::span<float> band_depth, int width, int band_first_row,
                ImageRect piece, std::span<const std::uint8_t> colour, std::span<const float> depth);

}  // namespace strata
