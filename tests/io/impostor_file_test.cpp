// The impostor atlas cache file (io/impostor_file.h): a round trip keeps every byte; a wrong key, a truncated or
// corrupted file reads as absent (never a half-loaded atlas); an incomplete atlas is not written.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "io/impostor_file.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

ImpostorAtlas small_atlas() {
  ImpostorAtlas a;
  a.layout.phases = 3;
  a.layout.azimuths = 4;
  a.layout.elevations = 2;
  a.layout.cell_width = 8;
  a.layout.cell_height = 16;
  a.key = 0x1234abcd5678ef00ull;
  a.speed_m_s = 1.3f;
  const std::size_t n = static_cast<std::size_t>(a.layout.phases) * a.layout.layer_bytes();
  a.color.resize(n);
  a.normal_depth.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    // Mostly empty, as a real atlas is, with some structure to compress.
    a.color[i] = (i / 4) % 7 == 0 ? static_cast<std::uint8_t>(i * 31) : 0;
    a.normal_depth[i] = (i / 4) % 5 == 0 ? static_cast<std::uint8_t>(i * 17 + 3) : 0;
  }
  return a;
}

TEST(ImpostorFile, RoundTripKeepsEveryByte) {
  const test::TempDir dir("impostor_file");
  const auto file = dir.path() / "atlas.bin";
  const ImpostorAtlas a = small_atlas();
  ASSERT_TRUE(a.complete());
  ASSERT_TRUE(save_impostor_atlas(file, a));
  const std::optional<ImpostorAtlas> b = load_impostor_atlas(file, a.key);
  ASSERT_TRUE(b.has_value());
  EXPECT_TRUE(b->from_cache);
  EXPECT_EQ(b->layout, a.layout);
  EXPECT_EQ(b->color, a.color);
  EXPECT_EQ(b->normal_depth, a.normal_depth);
  EXPECT_EQ(b->cell_width_m, a.cell_width_m);
  EXPECT_EQ(b->depth_range_m, a.depth_range_m);
  EXPECT_EQ(b->speed_m_s, a.speed_m_s);
  EXPECT_LT(std::filesystem::file_size(file), a.bytes()) << "stored compressed";
}

TEST(ImpostorFile, AStaleTruncatedOrCorruptFileReadsAsAbsent) {
  const test::TempDir dir("impostor_file");
  const auto file = dir.path() / "atlas.bin";
  const ImpostorAtlas a = small_atlas();
  ASSERT_TRUE(save_impostor_atlas(file, a));
  EXPECT_FALSE(load_impostor_atlas(file, a.key + 1).has_value()) << "another rig's or option's key";
  EXPECT_FALSE(load_impostor_atlas(dir.path() / "missing.bin", a.key).has_value());
  const auto size = std::filesystem::file_size(file);
  std::string bytes(size, '\0');
  std::ifstream(file, std::ios::binary).read(bytes.data(), static_cast<std::streamsize>(size));
  for (const std::size_t keep : {std::size_t(4), std::size_t(40), size / 2, size - 1}) {
    std::ofstream(file, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(keep));
    EXPECT_FALSE(load_impostor_atlas(file, a.key).has_value()) << "truncated to " << keep;
  }
  std::string corrupt = bytes;
  corrupt[corrupt.size() - 20] ^= 0x5a;  // inside the deflated normal-depth image
  std::ofstream(file, std::ios::binary | std::ios::trunc).write(corrupt.data(), static_cast<std::streamsize>(corrupt.size()));
  EXPECT_FALSE(load_impostor_atlas(file, a.key).has_value());
  std::string bad_layout = bytes;
  bad_layout[8 + 8] = 0;  // phases = 0 (the first layout field after the magic and the key)
  bad_layout[8 + 9] = 0;
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(bad_layout.data(), static_cast<std::streamsize>(bad_layout.size()));
  EXPECT_FALSE(load_impostor_atlas(file, a.key).has_value());
}

TEST(ImpostorFile, AnIncompleteAtlasIsNotWritten) {
  const test::TempDir dir("impostor_file");
  ImpostorAtlas a = small_atlas();
  a.color.pop_back();
  EXPECT_FALSE(a.complete());
  EXPECT_FALSE(save_impostor_atlas(dir.path() / "atlas.bin", a));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "atlas.bin"));
}

}  // namespace
}  // namespace strata
