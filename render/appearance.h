#pragma once
// Per-walker variety for --quality high: each walker's skin tone, hair, top, trousers and shoes, drawn from
// palettes of plausible colours by a key that stays with the walker (its entity slot), so a walker keeps
// its clothes while it changes level of detail or another walker is removed. Linear RGB, one colour per surface
// class (rig/surface_material.h); alpha is how skin-like the surface's shading is (1 skin, 0 cloth).
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "rig/surface_material.h"

namespace strata {

using WalkerPalette = std::array<glm::vec4, kSurfaceMaterialCount>;

// The palette of the walker with this key. Deterministic: the same key gives the same colours on every run.
WalkerPalette walker_palette(std::uint32_t key);
// The palette every walker gets when the renderer is given no keys: the default skin colour (sRGB, as in
// RenderOptions) everywhere but the eyes, so a body without clothes looks as it does at low quality, only lit better.
WalkerPalette plain_palette(const glm::vec3& skin_srgb);

// The palettes of `count` walkers, one after another (kSurfaceMaterialCount colours each), into `out`: by their
// keys, or all `plain` when there are none. What the body and impostor passes upload per frame.
void fill_palettes(const std::uint32_t* keys, std::size_t count, const WalkerPalette& plain, std::vector<glm::vec4>& out);

}  // namespace strata
