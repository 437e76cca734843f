// The body cache: a stored body comes back identical; anything else (other key, truncated or corrupt file,
// missing file) is refused so the caller regenerates.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "io/hanim_loader.h"
#include "rig/body_cache.h"
#include "tests/temp_dir.h"

namespace strata {
namespace {

namespace fs = std::filesystem;

Mesh tetra(const char* name, float scale) {
  Mesh m;
  m.name = name;
  m.positions = {{0, 0, 0}, {scale, 0, 0}, {0, scale, 0}, {0, 0, scale}};
  m.triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  m.part_names = {"hip", "head"};
  m.part = {0, 0, 1, 1};
  compute_normals(m);
  return m;
}

BodyLevels sample_body() {
  BodyLevels b;
  for (int l = 0; l < 3; ++l) b.levels[l] = tetra("level", 1.0f + l);
  b.cage = tetra("cage", 0.5f);
  for (std::size_t c = 0; c < b.levels[0].triangles.size(); ++c)  // face-varying texture coordinates on one level
    b.levels[0].corner_uvs.emplace_back(0.1f * float(c), 1.0f - 0.05f * float(c));
  return b;
}

TEST(BodyCache, RoundTripsExactly) {
  const test::TempDir tmp("strata_body_cache");
  const fs::path file = tmp / "strata" / "body.bin";  // the directory does not exist yet
  const BodyLevels body = sample_body();
  save_body_cache(file, 42, body);
  std::optional<BodyLevels> back = load_body_cache(file, 42);
  ASSERT_TRUE(back.has_value());
  for (int l = 0; l < 3; ++l) {
    EXPECT_EQ(back->levels[l].positions, body.levels[l].positions);
    EXPECT_EQ(back->levels[l].normals, body.levels[l].normals);
    EXPECT_EQ(back->levels[l].triangles, body.levels[l].triangles);
    EXPECT_EQ(back->levels[l].part, body.levels[l].part);
    EXPECT_EQ(back->levels[l].part_names, body.levels[l].part_names);
    EXPECT_EQ(back->levels[l].corner_uvs, body.levels[l].corner_uvs);
  }
  EXPECT_EQ(back->levels[0].corner_uvs.size(), 12u);
  EXPECT_EQ(back->cage.positions, body.cage.positions);
}

TEST(BodyCache, RefusesOtherKeysAndDamagedFiles) {
  const test::TempDir tmp("strata_body_cache");
  const fs::path file = tmp / "strata" / "body.bin";
  EXPECT_FALSE(load_body_cache(file, 42).has_value()) << "missing file";
  save_body_cache(file, 42, sample_body());
  EXPECT_FALSE(load_body_cache(file, 43).has_value()) << "stale key";
  const auto size = fs::file_size(file);
  fs::resize_file(file, size / 2);
  EXPECT_FALSE(load_body_cache(file, 42).has_value()) << "truncated";
  save_body_cache(file, 42, sample_body());
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size - 20));  // inside the cage's triangle indices or part names
    const char garbage[8] = {'\xff', '\xff', '\xff', '\xff', '\xff', '\xff', '\xff', '\x7f'};
    f.write(garbage, sizeof garbage);
  }
  EXPECT_FALSE(load_body_cache(file, 42).has_value()) << "corrupt";
}

TEST(BodyCache, KeyFollowsTheSkeletonAndOptions) {
  Skeleton skeleton = load_default_humanoid().skeleton;
  const BodyOptions options;
  const std::uint64_t key = body_cache_key(skeleton, options, 1);
  EXPECT_EQ(key, body_cache_key(skeleton, options, 1));
  EXPECT_NE(key, body_cache_key(skeleton, options, 2));
  BodyOptions finer = options;
  finer.grid_cell *= 0.9f;
  EXPECT_NE(key, body_cache_key(skeleton, finer, 1));
  skeleton.centers[3].y += 0.01f;
  EXPECT_NE(key, body_cache_key(skeleton, options, 1));
}

TEST(BodyCache, CanBeSwitchedOffAndRelocated) {
  setenv("STRATA_NO_BODY_CACHE", "1", 1);
  EXPECT_FALSE(body_cache_directory().has_value());
  unsetenv("STRATA_NO_BODY_CACHE");
  setenv("XDG_CACHE_HOME", "/tmp/strata-xdg", 1);
  ASSERT_TRUE(body_cache_directory().has_value());
  EXPECT_EQ(*body_cache_directory(), fs::path("/tmp/strata-xdg") / "strata");
}

}  // namespace
}  // namespace strata
