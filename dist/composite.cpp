#include "dist/composite.h"

#include <algorithm>
#include <cstring>
#include <iterator>
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

ImageRect clip_rect(ImageRect r, int width, int height) {
  r.x0 = std::max(r.x0, 0), r.y0 = std::max(r.y0, 0);
  r.x1 = std::min(r.x1, width), r.y1 = std::min(r.y1, height);
  return r.empty() ? ImageRect{} : r;
}

ImageRect band_piece(ImageRect footprint, int height, int pieces, int k) {
  const auto [first, last] = band_rows(height, pieces, k);
  ImageRect piece = footprint;
  piece.y0 = std::max(piece.y0, first), piece.y1 = std::min(piece.y1, last);
  return piece.empty() ? ImageRect{} : piece;
}

void pack_piece(std::span<const std::uint8_t> pixels, std::span<const float> depth, int width, ImageRect piece,
                std::vector<std::uint8_t>& colour_out, std::vector<float>& depth_out) {
  if (piece.empty()) return;
  const auto w = static_cast<std::size_t>(width);
  const auto row_px = static_cast<std::size_t>(piece.x1 - piece.x0);
  if (piece.x0 < 0 || piece.y0 < 0 || piece.x1 > width || static_cast<std::size_t>(piece.y1) * w > depth.size() ||
      pixels.size() != 4 * depth.size())
    throw std::invalid_argument("pack_piece: the piece is not inside the frame");
  for (int y = piece.y0; y < piece.y1; ++y) {
    const std::size_t i = static_cast<std::size_t>(y) * w + static_cast<std::size_t>(piece.x0);
    colour_out.insert(colour_out.end(), pixels.begin() + static_cast<std::ptrdiff_t>(4 * i),
                      pixels.begin() + static_cast<std::ptrdiff_t>(4 * (i + row_px)));
    depth_out.insert(depth_out.end(), depth.begin() + static_cast<std::ptrdiff_t>(i),
                     depth.begin() + static_cast<std::ptrdiff_t>(i + row_px));
  }
}

void fold_piece(std::span<std::uint8_t> band_pixels, std::span<float> band_depth, int width, int band_first_row,
                ImageRect piece, std::span<const std::uint8_t> colour, std::span<const float> depth) {
  if (piece.empty()) {
    if (!colour.empty() || !depth.empty()) throw std::invalid_argument("fold_piece: pixels for an empty piece");
    return;
  }
  const auto w = static_cast<std::size_t>(width);
  const auto row_px = static_cast<std::size_t>(piece.x1 - piece.x0);
  if (colour.size() != 4 * piece.area() || depth.size() != piece.area() || piece.x0 < 0 || piece.x1 > width ||
      piece.y0 < band_first_row || static_cast<std::size_t>(piece.y1 - band_first_row) * w > band_depth.size() ||
      band_pixels.size() != 4 * band_depth.size())
    throw std::invalid_argument("fold_piece: the piece does not fit the band");
  for (int y = piece.y0; y < piece.y1; ++y) {
    const std::size_t i = static_cast<std::size_t>(y - band_first_row) * w + static_cast<std::size_t>(piece.x0);
    const std::size_t row = static_cast<std::size_t>(y - piece.y0) * row_px;
    composite_nearest(band_pixels.subspan(4 * i, 4 * row_px), band_depth.subspan(i, row_px),
                      colour.subspan(4 * row, 4 * row_px), depth.subspan(row, row_px));
  }
}

}  // namespace strata
