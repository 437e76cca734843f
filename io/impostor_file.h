#pragma once
// The impostor atlas cache file (components/impostor_atlas.h): a magic, the key the atlas was baked for, the
// layout and cell geometry, then both images deflated (zlib). Most texels are empty (a walker covers about a
// quarter of its cell), so the 67 MB of the default atlas store as a few MB and load in a fraction of the bake's
// time. Written atomically (io/atomic_file.h); a missing, stale, truncated or corrupt file reads as absent, so a
// bad cache costs a rebake and never a half-loaded atlas. PNG files were the alternative: readable with any
// viewer but 32 of them per atlas, and ~3x slower to write through OpenImageIO than one deflate pass.
#include <cstdint>
#include <filesystem>
#include <optional>

#include "components/impostor_atlas.h"

namespace strata {

// The atlas stored in `file` under `key`; nullopt when absent or unusable for any reason (never throws).
std::optional<ImpostorAtlas> load_impostor_atlas(const std::filesystem::path& file, std::uint64_t key);
// Stores a complete atlas (key = atlas.key); false when it could not be written (the cache is an optimisation:
// callers go on without it).
bool save_impostor_atlas(const std::filesystem::path& file, const ImpostorAtlas& atlas);

}  // namespace strata
