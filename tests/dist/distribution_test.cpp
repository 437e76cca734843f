// One crowd over several processes, without MPI: the slab partition, the compositing rules, the ownership job,
// migration, and the claim the distributed run rests on — walkers animated by the process owning their slab, the
// others only advancing their gait clock, and a walker's row sent to its new owner when it crosses a border,
// give every walker exactly the state one process gives it. tests/apps/mpi_crowd_test.cpp runs the same through mpirun.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "dist/composite.h"
#include "dist/migration.h"
#include "dist/partition.h"
#include "io/hanim_loader.h"
#include "rig/body_rig.h"
#include "scene/body_settings.h"
#include "scene/crowd.h"
#include "scene/spawn.h"
#include "scene/state_hash.h"
#include "scene/step.h"
#include "systems/ownership.h"

namespace strata {
namespace {

TEST(Partition, SlabsHoldEqualSharesAlongTheLongerAxis) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> along(-40.0f, 10.0f), across(-3.0f, 3.0f);
  std::vector<float> xs(1000), zs(1000);
  for (std::size_t i = 0; i < xs.size(); ++i) xs[i] = across(rng), zs[i] = along(rng);
  for (int ranks : {1, 2, 3, 4, 7}) {
    const CrowdPartition p = partition_by_density(xs, zs, ranks);
    EXPECT_EQ(p.ranks(), ranks);
    EXPECT_EQ(p.axis, 2) << "z spans 50 m, x 6 m";
    EXPECT_TRUE(std::is_sorted(p.cuts.begin(), p.cuts.end()));
    const std::vector<std::size_t> n = walkers_per_rank(p, xs, zs);
    for (std::size_t k = 0; k < n.size(); ++k) {
      EXPECT_NEAR(static_cast<double>(n[k]), 1000.0 / ranks, 1.0) << ranks << " ranks, slab " << k;
      // owner() and region() agree walker by walker.
      const OwnershipRegion r = p.region(static_cast<int>(k));
      for (std::size_t i = 0; i < xs.size(); ++i)
        EXPECT_EQ(r.owns(xs[i], zs[i]), p.owner(xs[i], zs[i]) == static_cast<int>(k));
    }
  }
}

TEST(Partition, DependsOnThePositionsNotTheirOrderAndIgnoresNonFinite) {
  std::vector<float> xs = {3, -1, 8, 2, 5, 0, 7, 1}, zs(8, 0.0f);
  const CrowdPartition a = partition_by_density(xs, zs, 3);
  std::reverse(xs.begin(), xs.end());
  xs.push_back(std::numeric_limits<float>::quiet_NaN());
  zs.push_back(0.0f);
  const CrowdPartition b = partition_by_density(xs, zs, 3);
  EXPECT_EQ(a.cuts, b.cuts);
  EXPECT_EQ(b.owner(xs.back(), 0.0f), -1);
  // Every finite point is somebody's, also exactly on a cut.
  for (float c : a.cuts) EXPECT_GE(a.owner(c, 0.0f), 0);
  // No walkers: still a partition, every coordinate owned.
  const CrowdPartition empty = partition_by_density({}, {}, 4);
  EXPECT_EQ(empty.ranks(), 4);
  EXPECT_GE(empty.owner(12.0f, -3.0f), 0);
  EXPECT_THROW(partition_by_density(xs, zs, 0), std::invalid_argument);
}

TEST(Composite, NearestWinsTiesKeepTheDarkerAndOrderDoesNotMatter) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> byte(0, 255), level(0, 3);
  const std::size_t n = 4096;
  const int pieces = 4;
  std::vector<std::vector<std::uint8_t>> colour(pieces, std::vector<std::uint8_t>(4 * n));
  std::vector<std::vector<float>> depth(pieces, std::vector<float>(n));
  for (int k = 0; k < pieces; ++k)
    for (std::size_t i = 0; i < n; ++i) {
      depth[k][i] = 0.25f * static_cast<float>(level(rng));  // many ties on purpose
      for (int c = 0; c < 4; ++c) colour[k][4 * i + c] = static_cast<std::uint8_t>(byte(rng));
    }
  const auto fold = [&](std::vector<int> order) {
    std::vector<std::uint8_t> acc(4 * n, 255);
    std::vector<float> d(n, 1.0f);
    for (int k : order) composite_nearest(acc, d, colour[k], depth[k]);
    return std::make_pair(acc, d);
  };
  const auto a = fold({0, 1, 2, 3}), b = fold({3, 1, 0, 2});
  EXPECT_EQ(a.first, b.first);
  EXPECT_EQ(a.second, b.second);
  for (std::size_t i = 0; i < n; ++i) {
    float nearest = 1.0f;
    for (int k = 0; k < pieces; ++k) nearest = std::min(nearest, depth[k][i]);
    ASSERT_EQ(a.second[i], nearest);
    for (int c = 0; c < 4; ++c) {
      int expected = 255;
      for (int k = 0; k < pieces; ++k)
        if (depth[k][i] == nearest) expected = std::min<int>(expected, colour[k][4 * i + c]);
      ASSERT_EQ(a.first[4 * i + c], expected) << "pixel " << i;
    }
  }
  std::vector<std::uint8_t> small(8);
  std::vector<float> one(1);
  EXPECT_THROW(composite_nearest(small, one, colour[0], depth[0]), std::invalid_argument);
}

TEST(Composite, BandsCoverEveryRowOnce) {
  for (int height : {1, 7, 720}) for (int pieces : {1, 2, 3, 4, 8}) {
    int next = 0;
    for (int k = 0; k < pieces; ++k) {
      const auto [first, last] = band_rows(height, pieces, k);
      EXPECT_EQ(first, next);
      EXPECT_LE(last - first, height / pieces + 1);
      next = last;
    }
    EXPECT_EQ(next, height);
  }
  EXPECT_THROW(band_rows(10, 2, 2), std::invalid_argument);
}

TEST(Ownership, CullsWalkersOutsideTheSlabAndRefusesBadInput) {
  const std::vector<float> placement = {-2, 0, 1, 5, /*y*/ 0, 0, 0, 0, /*z*/ 0, 0, 0, 0};  // x row, y row, z row
  std::vector<std::uint8_t> decided = {0, 1, 2, 6};
  OwnershipRegion region{0, 0.0f, 2.0f};
  OwnershipJob job;
  job.region = &region;
  job.culled_slot = 4;
  job.walkers = 4;
  job.stride = 4;
  job.placement = placement.data();
  job.decided = decided;
  ASSERT_TRUE(job.run());
  EXPECT_EQ(decided, (std::vector<std::uint8_t>{4, 1, 2, 4}));
  region.lo = 3.0f;  // lo > hi
  EXPECT_FALSE(job.validate());
  region = {1, 0.0f, 1.0f};  // axis must be x or z
  EXPECT_FALSE(job.validate());
}

// The default walking crowd at level 0 over `ranks` crowds, each animating only its slab (recut every
// `recut_frames`), against one crowd animating everything: every walker's digest at the end equals the single
// crowd's, from whichever crowd owned it in the last step.
void expect_partitioned_crowd_matches(int ranks, int frames, int recut_frames) {
  const auto make = [] {
    Rig rig = to_rig(load_default_humanoid());
    rig.body = default_bound_body();
    auto crowd = std::make_unique<Crowd>(rig);
    CrowdConfig config;
    config.walkers = 10;
    config.motion = MotionSource::Walk;
    spawn_crowd(*crowd, config);
    set_detail_level(*crowd, DetailLevel::mesh(2));
    return crowd;
  };
  auto single = make();
  std::vector<std::unique_ptr<Crowd>> parts;
  for (int r = 0; r < ranks; ++r) parts.push_back(make());
  Profiler profiler(4, false);
  const float dt = 1.0f / 30.0f;
  CrowdPartition partition;
  std::vector<int> owner;
  std::size_t owner_changes = 0;
  for (int f = 0; f < frames; ++f) {
    const std::vector<Entity> walkers = single->world.entities();
    std::vector<float> xs, zs;
    for (const Entity e : walkers) {
      const EntityLocation at = parts[0]->world.location(e);
      const SoaTable& t = parts[0]->world.table(at.table);
      xs.push_back(t.f32(kWalkerPlacement, 0)[at.block]);
      zs.push_back(t.f32(kWalkerPlacement, 2)[at.block]);
    }
    if (f % recut_frames == 0) partition = partition_by_density(xs, zs, ranks);
    std::vector<int> now(walkers.size());
    for (std::size_t i = 0; i < walkers.size(); ++i) now[i] = partition.owner(xs[i], zs[i]);
    if (!owner.empty())
      for (std::size_t i = 0; i < now.size(); ++i)
        if (now[i] != owner[i]) {
          // The old owner's row travels to the new owner (dist/migration.h), as MPI carries it between processes.
          ++owner_changes;
          std::vector<std::uint8_t> bytes;
          pack_walkers(*parts[static_cast<std::size_t>(owner[i])], std::span<const Entity>(&walkers[i], 1), bytes);
          EXPECT_EQ(unpack_walkers(*parts[static_cast<std::size_t>(now[i])], bytes), 1u);
        }
    owner = now;
    for (int r = 0; r < ranks; ++r) {
      parts[static_cast<std::size_t>(r)]->lod.ownership = partition.region(r);
      step(*parts[static_cast<std::size_t>(r)], dt, profiler);
    }
    step(*single, dt, profiler);
  }
  const std::vector<Entity> walkers = single->world.entities();
  std::size_t culled_somewhere = 0;
  for (std::size_t i = 0; i < walkers.size(); ++i) {
    ASSERT_GE(owner[i], 0);
    const Crowd& by_owner = *parts[static_cast<std::size_t>(owner[i])];
    EXPECT_EQ(walker_state_digest(by_owner, walkers[i]), walker_state_digest(*single, walkers[i])) << "walker " << i;
    for (int r = 0; r < ranks; ++r)
      if (r != owner[i]) culled_somewhere += parts[static_cast<std::size_t>(r)]->slot_of(walkers[i]) == DetailSlot::Culled;
  }
  EXPECT_EQ(culled_somewhere, walkers.size() * static_cast<std::size_t>(ranks - 1))
      << "a walker is kept culled by every rank but its owner";
  EXPECT_GT(owner_changes, 0u) << "the run must move some walkers across a border to test anything";
}

TEST(PartitionedCrowd, EveryWalkerMatchesOneProcessAcrossBorderCrossings) {
  expect_partitioned_crowd_matches(2, 90, 1000);  // fixed slabs: walkers on the track cross the cut
  expect_partitioned_crowd_matches(3, 60, 15);    // recut every half second
}

}  // namespace
}  // namespace strata
