// Per-walker appearance (render/appearance.h): the same key always gives the same colours, colours are valid
// linear values with the right material response, and a crowd's keys spread over the palettes.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <tuple>

#include "render/appearance.h"

namespace strata {
namespace {

std::tuple<float, float, float> rgb(const glm::vec4& c) { return {c.r, c.g, c.b}; }
const glm::vec4& of(const WalkerPalette& p, SurfaceMaterial m) { return p[static_cast<std::size_t>(m)]; }

TEST(Appearance, SameKeySameColoursAndValidValues) {
  for (std::uint32_t key = 0; key < 500; ++key) {
    const WalkerPalette a = walker_palette(key), b = walker_palette(key);
    ASSERT_EQ(a, b);
    for (const glm::vec4& c : a)
      for (int k = 0; k < 4; ++k) {
        ASSERT_GE(c[k], 0.0f);
        ASSERT_LE(c[k], 1.0f);
      }
    EXPECT_EQ(of(a, SurfaceMaterial::Skin).a, 1.0f) << "skin is shaded as skin";
    for (SurfaceMaterial cloth : {SurfaceMaterial::Top, SurfaceMaterial::Bottom, SurfaceMaterial::Shoes})
      EXPECT_EQ(of(a, cloth).a, 0.0f) << "cloth is shaded as cloth";
  }
}

TEST(Appearance, ACrowdIsDressedInManyColours) {
  std::set<std::tuple<float, float, float>> skins, tops, bottoms, hair;
  std::size_t same_as_next = 0;
  for (std::uint32_t key = 1; key <= 200; ++key) {
    const WalkerPalette p = walker_palette(key);
    skins.insert(rgb(of(p, SurfaceMaterial::Skin)));
    tops.insert(rgb(of(p, SurfaceMaterial::Top)));
    bottoms.insert(rgb(of(p, SurfaceMaterial::Bottom)));
    hair.insert(rgb(of(p, SurfaceMaterial::Hair)));
    // Consecutive keys (entity slots spawned one after another) must not look alike.
    const WalkerPalette next = walker_palette(key + 1);
    same_as_next += of(p, SurfaceMaterial::Top) == of(next, SurfaceMaterial::Top) &&
                    of(p, SurfaceMaterial::Skin) == of(next, SurfaceMaterial::Skin);
  }
  EXPECT_GE(skins.size(), 8u);
  EXPECT_GE(tops.size(), 10u);
  EXPECT_GE(bottoms.size(), 6u);
  EXPECT_GE(hair.size(), 7u);
  EXPECT_LT(same_as_next, 10u);
}

// Walkers spawned together get consecutive keys and stand side by side: neighbours never share a shirt, and in any
// twelve consecutive keys no shirt appears more than twice.
TEST(Appearance, NeighbouringKeysWearDifferentShirts) {
  for (std::uint32_t start = 0; start < 1000; ++start) {
    ASSERT_NE(of(walker_palette(start), SurfaceMaterial::Top), of(walker_palette(start + 1), SurfaceMaterial::Top)) << start;
    std::map<std::tuple<float, float, float>, int> count;
    for (std::uint32_t k = start; k < start + 12; ++k) ++count[rgb(of(walker_palette(k), SurfaceMaterial::Top))];
    for (const auto& [colour, n] : count) ASSERT_LE(n, 2) << "keys " << start << ".." << start + 11;
  }
}

TEST(Appearance, ThePlainPaletteIsTheSkinColourButForTheEyes) {
  const WalkerPalette p = plain_palette({0.8f, 0.62f, 0.52f});
  const glm::vec4 skin = of(p, SurfaceMaterial::Skin);
  EXPECT_GT(skin.r, skin.b) << "linear, still warm";
  EXPECT_LT(skin.r, 0.8f) << "made linear from sRGB";
  for (SurfaceMaterial m : {SurfaceMaterial::Top, SurfaceMaterial::Bottom, SurfaceMaterial::Shoes, SurfaceMaterial::Hair})
    EXPECT_EQ(of(p, m), skin);
  EXPECT_NE(of(p, SurfaceMaterial::Sclera), skin);
}

}  // namespace
}  // namespace strata
