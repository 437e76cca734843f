#pragma once
// Writes images through OpenImageIO. PNG uses compression level 1: ~3x faster than the default at a modest size
// cost, which matters when the crowd job writes every frame (rendering-and-profiling notes, section 1).
#include <cstdint>
#include <filesystem>
#include <span>

namespace strata {

// `pixels`: rows top to bottom, `channels` (3 or 4) uint8 per pixel. Throws std::runtime_error naming the path.
void write_image(const std::filesystem::path& path, int width, int height, int channels,
                 std::span<const std::uint8_t> pixels);

}  // namespace strata
