#include "render/appearance.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

namespace strata {
namespace {

struct Srgb {
  float r, g, b;
};

// Skin tones from light to dark, after measured skin reflectance (sRGB); every tone appears in a crowd.
constexpr Srgb kSkin[] = {{0.96f, 0.80f, 0.69f}, {0.93f, 0.75f, 0.63f}, {0.87f, 0.66f, 0.53f}, {0.78f, 0.57f, 0.44f},
                          {0.66f, 0.47f, 0.34f}, {0.54f, 0.37f, 0.26f}, {0.42f, 0.28f, 0.19f}, {0.31f, 0.20f, 0.14f}};
constexpr Srgb kHair[] = {{0.08f, 0.06f, 0.05f}, {0.17f, 0.11f, 0.07f}, {0.30f, 0.19f, 0.11f}, {0.47f, 0.33f, 0.20f},
                          {0.72f, 0.58f, 0.38f}, {0.45f, 0.22f, 0.12f}, {0.62f, 0.60f, 0.57f}};
// Shirts: muted everyday colours, a few brighter ones.
constexpr Srgb kTop[] = {{0.85f, 0.85f, 0.83f}, {0.18f, 0.22f, 0.33f}, {0.55f, 0.15f, 0.15f}, {0.25f, 0.40f, 0.30f},
                         {0.80f, 0.65f, 0.30f}, {0.35f, 0.50f, 0.70f}, {0.20f, 0.20f, 0.22f}, {0.60f, 0.45f, 0.60f},
                         {0.90f, 0.50f, 0.25f}, {0.45f, 0.45f, 0.47f}};
// Trousers: denim, greys, khaki, black.
constexpr Srgb kBottom[] = {{0.20f, 0.27f, 0.42f}, {0.32f, 0.40f, 0.55f}, {0.15f, 0.15f, 0.17f}, {0.40f, 0.40f, 0.42f},
                            {0.62f, 0.55f, 0.40f}, {0.30f, 0.24f, 0.18f}};
constexpr Srgb kShoes[] = {{0.10f, 0.09f, 0.09f}, {0.85f, 0.85f, 0.83f}, {0.35f, 0.22f, 0.13f}, {0.25f, 0.25f, 0.28f}};
constexpr Srgb kIris[] = {{0.20f, 0.13f, 0.09f}, {0.30f, 0.20f, 0.12f}, {0.25f, 0.35f, 0.45f}, {0.30f, 0.35f, 0.22f}};
constexpr Srgb kSclera = {0.86f, 0.83f, 0.80f};

float to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }
glm::vec4 linear(const Srgb& c, float skin) { return {to_linear(c.r), to_linear(c.g), to_linear(c.b), skin}; }

// splitmix64's finaliser: consecutive keys (entity slots 0, 1, 2...) land on unrelated palettes.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Entry of a table of `n` by a Weyl sequence: frac(key * step) for an irrational step. Keys handed out one after
// another (entity slots of a crowd spawned together, standing side by side) land far apart in the table and use
// it evenly; hashing alone dressed five walkers in a row in the same green shirt (keys 2..6).
std::size_t spread(std::uint32_t key, double step, std::size_t n) {
  const double f = static_cast<double>(key) * step;
  return static_cast<std::size_t>((f - std::floor(f)) * static_cast<double>(n)) % n;
}

// A table made linear once: walker_palette runs per walker per frame (every impostor of a crowd), and the sRGB
// curve's pow() for its 21 channels cost more than the rest of it.
template <std::size_t N>
std::array<glm::vec3, N> linear_table(const Srgb (&table)[N]) {
  std::array<glm::vec3, N> out;
  for (std::size_t i = 0; i < N; ++i) out[i] = glm::vec3(linear(table[i], 0.0f));
  return out;
}

}  // namespace

WalkerPalette walker_palette(std::uint32_t key) {
  static const auto skin = linear_table(kSkin);
  static const auto top = linear_table(kTop);
  static const auto bottom = linear_table(kBottom);
  static const auto shoes = linear_table(kShoes);
  static const auto hair = linear_table(kHair);
  static const auto iris = linear_table(kIris);
  static const glm::vec3 sclera(linear(kSclera, 0.0f));
  const std::uint64_t h = mix(key), g = mix(h);
  WalkerPalette p;
  // The two largest areas, skin and shirt, by Weyl sequences with different steps (sqrt 3 - 1, sqrt 2 - 1), so
  // neighbours differ in both; the rest by the hash.
  p[static_cast<std::size_t>(SurfaceMaterial::Skin)] = glm::vec4(skin[spread(key, 0.7320508075688772, skin.size())], 1.0f);
  p[static_cast<std::size_t>(SurfaceMaterial::Top)] = glm::vec4(top[spread(key, 0.4142135623730951, top.size())], 0.0f);
  p[static_cast<std::size_t>(SurfaceMaterial::Bottom)] = glm::vec4(bottom[(h >> 32) % bottom.size()], 0.0f);
  p[static_cast<std::size_t>(SurfaceMaterial::Shoes)] = glm::vec4(shoes[(h >> 48) % shoes.size()], 0.0f);
  // Hair is drawn apart from skin: dark skin with light hair is rarer than the reverse but happens.
  p[static_cast<std::size_t>(SurfaceMaterial::Hair)] = glm::vec4(hair[g % hair.size()], 0.15f);
  p[static_cast<std::size_t>(SurfaceMaterial::Eyes)] = glm::vec4(iris[(g >> 20) % iris.size()], 0.3f);
  p[static_cast<std::size_t>(SurfaceMaterial::Sclera)] = glm::vec4(sclera, 0.3f);
  return p;
}

WalkerPalette plain_palette(const glm::vec3& skin_srgb) {
  WalkerPalette p;
  p.fill(linear({skin_srgb.r, skin_srgb.g, skin_srgb.b}, 1.0f));
  p[static_cast<std::size_t>(SurfaceMaterial::Eyes)] = linear(kIris[0], 0.3f);
  p[static_cast<std::size_t>(SurfaceMaterial::Sclera)] = linear(kSclera, 0.3f);
  return p;
}

void fill_palettes(const std::uint32_t* keys, std::size_t count, const WalkerPalette& plain, std::vector<glm::vec4>& out) {
  out.resize(count * kSurfaceMaterialCount);
  for (std::size_t w = 0; w < count; ++w) {
    const WalkerPalette p = keys ? walker_palette(keys[w]) : plain;
    std::copy(p.begin(), p.end(), out.begin() + static_cast<std::ptrdiff_t>(w * kSurfaceMaterialCount));
  }
}

}  // namespace strata
