// One crowd over several processes, without MPI: the slab partition, the compositing rules, the ownership job,
// migration, the agents' exchange, and the claim the distributed run rests on — walkers held and animated only by
// the process owning their slab, and a walker's row sent to its new owner when it crosses a border, give every
// walker exactly the state one process gives it. tests/apps/mpi_crowd_test.cpp runs the same through mpirun.
#include <gtest/gtest.h>

#include <algorithm>
#include <barrier>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

#include "dist/agent_exchange.h"
#include "dist/composite.h"
#include "dist/migration.h"
#include "dist/partition.h"
#include "io/hanim_loader.h"
#include "io/scenario_file.h"
#include "rig/body_rig.h"
#include "scene/body_settings.h"
#include "scene/crowd.h"
#include "scene/crowd_agents.h"
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

TEST(Partition, HistogramCutsAreTheSameForAnySplitOfTheWalkersAndBalanceToABin) {
  std::mt19937 rng(11);
  std::normal_distribution<float> along(0.0f, 30.0f);
  std::uniform_real_distribution<float> across(-10.0f, 10.0f);
  std::vector<float> xs, zs;
  for (int i = 0; i < 20000; ++i) xs.push_back(along(rng)), zs.push_back(across(rng));
  xs.push_back(std::numeric_limits<float>::quiet_NaN()), zs.push_back(0.0f);  // ignored
  const float lo_x = *std::min_element(xs.begin(), xs.end() - 1), hi_x = *std::max_element(xs.begin(), xs.end() - 1);
  const PlacementHistogram whole = placement_histogram(xs, zs, lo_x, hi_x, -10.0f, 10.0f);
  // Three processes holding interleaved thirds, their histograms summed as MpiWorld::sum does.
  PlacementHistogram sum = placement_histogram({}, {}, lo_x, hi_x, -10.0f, 10.0f);
  for (int part = 0; part < 3; ++part) {
    std::vector<float> px, pz;
    for (std::size_t i = static_cast<std::size_t>(part); i < xs.size(); i += 3) px.push_back(xs[i]), pz.push_back(zs[i]);
    const PlacementHistogram h = placement_histogram(px, pz, lo_x, hi_x, -10.0f, 10.0f);
    for (std::size_t b = 0; b < kPartitionBins; ++b) sum.x[b] += h.x[b], sum.z[b] += h.z[b];
  }
  EXPECT_EQ(sum.x, whole.x);
  const CrowdPartition p = partition_from_histogram(sum, 4);
  EXPECT_EQ(p.axis, 0);
  ASSERT_EQ(p.cuts.size(), 3u);
  EXPECT_TRUE(std::is_sorted(p.cuts.begin(), p.cuts.end()));
  const std::uint32_t fullest = *std::max_element(whole.x.begin(), whole.x.end());
  for (const std::size_t n : walkers_per_rank(p, xs, zs))
    EXPECT_NEAR(static_cast<double>(n), 5000.0, static_cast<double>(fullest) + 1.0) << "balanced to within a bin";
  // Against the exact cuts from every placement: within one bin's width.
  const CrowdPartition exact = partition_by_density(xs, zs, 4);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(p.cuts[k], exact.cuts[k], (hi_x - lo_x) / kPartitionBins);
  EXPECT_THROW(partition_from_histogram(PlacementHistogram{}, 2), std::invalid_argument);
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

// Footprints (dist/composite.h): K frames that share a background and each hold their own "walkers" inside their
// footprint, composited as MpiWorld::composite does it (each band's owner starts from its own frame and folds in
// the others' pieces of the band, packed and unpacked), give the image of folding the whole frames; a footprint
// that leaves out one of its walkers does not (the test can fail). Bad pieces are refused.
TEST(Composite, FootprintsGiveTheWholeFramesImage) {
  const int width = 61, height = 37, ranks = 3;
  const std::size_t n = static_cast<std::size_t>(width) * height;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> byte(0, 255);
  std::vector<std::uint8_t> shared_colour(4 * n);
  std::vector<float> shared_depth(n);
  for (std::size_t i = 0; i < n; ++i) {
    shared_depth[i] = i < n / 3 ? 1.0f : 0.9f - 0.0001f * static_cast<float>(i % 97);
    for (int c = 0; c < 4; ++c) shared_colour[4 * i + c] = static_cast<std::uint8_t>(byte(rng));
  }
  std::vector<std::vector<std::uint8_t>> colour(ranks, shared_colour);
  std::vector<std::vector<float>> depth(ranks, shared_depth);
  std::vector<ImageRect> footprint(ranks);
  const ImageRect boxes[ranks][2] = {{{2, 3, 20, 30}, {15, 25, 33, 36}},  // each rank: two walkers, overlapping others'
                                     {{18, 0, 40, 12}, {30, 10, 50, 35}},
                                     {{45, 5, 61, 37}, {0, 33, 8, 37}}};
  for (int r = 0; r < ranks; ++r) {
    footprint[r] = {width, height, 0, 0};
    for (const ImageRect& b : boxes[r]) {
      footprint[r] = {std::min(footprint[r].x0, b.x0), std::min(footprint[r].y0, b.y0), std::max(footprint[r].x1, b.x1),
                      std::max(footprint[r].y1, b.y1)};
      for (int y = b.y0; y < b.y1; ++y)
        for (int x = b.x0; x < b.x1; ++x) {
          const std::size_t i = static_cast<std::size_t>(y) * width + static_cast<std::size_t>(x);
          // Nearer than the background, or a shadow on it (same depth, darker): both kinds a walker makes.
          if ((x + y + r) % 3 == 0) {
            for (int c = 0; c < 3; ++c) colour[r][4 * i + c] = static_cast<std::uint8_t>(colour[r][4 * i + c] / 2);
          } else {
            depth[r][i] = 0.5f - 0.01f * static_cast<float>((x * 7 + y * 3 + r) % 13);
            for (int c = 0; c < 4; ++c) colour[r][4 * i + c] = static_cast<std::uint8_t>(byte(rng));
          }
        }
    }
  }
  std::vector<std::uint8_t> whole = colour[0];
  std::vector<float> whole_depth = depth[0];
  for (int r = 1; r < ranks; ++r) composite_nearest(whole, whole_depth, colour[r], depth[r]);
  const auto by_footprints = [&](const std::vector<ImageRect>& fp) {
    std::vector<std::uint8_t> image;
    for (int k = 0; k < ranks; ++k) {
      const auto [first, last] = band_rows(height, ranks, k);
      const std::size_t at = static_cast<std::size_t>(first) * width, band = static_cast<std::size_t>(last - first) * width;
      std::vector<std::uint8_t> band_colour(colour[k].begin() + 4 * at, colour[k].begin() + 4 * (at + band));
      std::vector<float> band_depth(depth[k].begin() + at, depth[k].begin() + at + band);
      for (int r = 0; r < ranks; ++r) {
        if (r == k) continue;
        const ImageRect piece = band_piece(clip_rect(fp[r], width, height), height, ranks, k);
        std::vector<std::uint8_t> piece_colour;
        std::vector<float> piece_depth;
        pack_piece(colour[r], depth[r], width, piece, piece_colour, piece_depth);
        EXPECT_EQ(piece_depth.size(), piece.area());
        fold_piece(band_colour, band_depth, width, first, piece, piece_colour, piece_depth);
      }
      image.insert(image.end(), band_colour.begin(), band_colour.end());
    }
    return image;
  };
  EXPECT_EQ(by_footprints(footprint), whole);
  std::vector<ImageRect> wide = footprint;  // grown past the frame: clipped, the same image
  for (ImageRect& f : wide) f = {f.x0 - 5, f.y0 - 5, f.x1 + 9, f.y1 + 9};
  EXPECT_EQ(by_footprints(wide), whole);
  std::vector<ImageRect> short_of_one = footprint;
  short_of_one[1] = boxes[1][0];  // leaves rank 1's second walker out
  EXPECT_NE(by_footprints(short_of_one), whole);

  EXPECT_EQ(clip_rect({-3, -3, -1, 5}, width, height), ImageRect{});
  EXPECT_EQ(band_piece({0, 0, width, 5}, height, ranks, 2), ImageRect{});
  std::vector<std::uint8_t> band_colour(4 * 13 * width);
  std::vector<float> band_depth(13 * width);
  std::vector<std::uint8_t> four_colour(4 * 4), eight_colour(4 * 8);
  std::vector<float> four_depth(4), eight_depth(8);
  EXPECT_THROW(fold_piece(band_colour, band_depth, width, 0, {0, 0, 2, 3}, four_colour, four_depth), std::invalid_argument)
      << "too few pixels";
  EXPECT_THROW(fold_piece(band_colour, band_depth, width, 0, {0, 0, 2, 2}, four_colour, eight_depth), std::invalid_argument)
      << "colour and depth disagree";
  EXPECT_THROW(fold_piece(band_colour, band_depth, width, 5, {0, 0, 2, 2}, four_colour, four_depth), std::invalid_argument)
      << "above the band";
  EXPECT_THROW(fold_piece(band_colour, band_depth, width, 0, {0, 10, 2, 14}, eight_colour, eight_depth), std::invalid_argument)
      << "below it";
  EXPECT_THROW(pack_piece(colour[0], depth[0], width, {0, 30, 2, 40}, four_colour, four_depth), std::invalid_argument);
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

TEST(AgentExchange, GhostsAreTheAgentsWithinReachOfAnotherSlab) {
  CrowdPartition partition;
  partition.axis = 0;
  partition.cuts = {0.0f, 10.0f};  // slabs (-inf, 0), [0, 10), [10, inf)
  std::vector<AgentSnapshot> mine;
  for (const float x : {-30.0f, -8.5f, -1.0f, 4.0f, 12.0f, 18.9f, 19.5f, 40.0f})
    mine.push_back({static_cast<std::uint32_t>(mine.size()), x, 2.0f, 0.1f, 0.0f, 1.0f, 0.0f, 0.3f, 1.5f});
  const float reach = 9.0f;
  const auto to_rank = pack_ghosts(mine, partition, 1, reach);
  ASSERT_EQ(to_rank.size(), 3u);
  EXPECT_TRUE(to_rank[1].empty()) << "nothing is sent to oneself";
  std::vector<AgentSnapshot> got0, got2;
  unpack_ghosts(to_rank[0], got0);
  unpack_ghosts(to_rank[2], got2);
  const auto walkers = [](const std::vector<AgentSnapshot>& v) {
    std::vector<std::uint32_t> w;
    for (const AgentSnapshot& a : v) w.push_back(a.walker);
    return w;
  };
  EXPECT_EQ(walkers(got0), (std::vector<std::uint32_t>{0, 1, 2, 3})) << "x < 0 + 9";
  EXPECT_EQ(walkers(got2), (std::vector<std::uint32_t>{3, 4, 5, 6, 7})) << "x >= 10 - 9";
  EXPECT_EQ(got2[1].px, 12.0f);
  EXPECT_EQ(got2[1].radius, 0.3f);
  EXPECT_EQ(got2[1].max_speed, 1.5f);
  // Malformed bytes append nothing.
  std::vector<std::uint8_t> cut(to_rank[0].begin(), to_rank[0].end() - 1);
  std::vector<AgentSnapshot> none;
  EXPECT_THROW(unpack_ghosts(cut, none), std::runtime_error);
  mine[0].radius = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(unpack_ghosts(pack_ghosts(mine, partition, 1, reach)[0], none), std::runtime_error);
  EXPECT_TRUE(none.empty());
  EXPECT_GT(ghost_reach(AvoidanceParameters{}), 2.0f * AvoidanceParameters{}.neighbor_distance);
}

// `strata report crowd` over ranks (scene/crowd_metrics.h): agents wandering over three slabs, often touching
// across the cuts, changing owner as they cross, arriving, getting stuck, one of them NaN. Each "rank" observes
// the agents it owns with the others' within reach of its slab (pack/unpack_border_observations, as the bytes
// travel), rank 0 merges the packed metrics: every figure equals one observer's of the whole crowd. Without the
// border observations the overlaps across the cuts are missed (the test can fail); malformed bytes are refused.
TEST(CrowdMetricsOverRanks, PiecesMergeIntoOneObserversFigures) {
  const int ranks = 3, agents = 240, frames = 60;
  const float dt = 1.0f / 30.0f;
  CrowdPartition partition;
  partition.axis = 0;
  partition.cuts = {-4.0f, 4.0f};
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<AgentObservation> crowd(agents);
  for (int a = 0; a < agents; ++a) {
    AgentObservation& o = crowd[a];
    o.walker = static_cast<std::uint32_t>(a * 3 + 1);  // sparse entity indices
    // Pairs: the odd agent of each pair stands 0.5 m (an overlap of 0.1 m) from the even one, many across a cut.
    o.x = a % 2 == 0 ? -12.0f + 24.0f * unit(rng) : crowd[a - 1].x + 0.5f;
    o.z = a % 2 == 0 ? 10.0f * unit(rng) : crowd[a - 1].z;
    o.radius = 0.3f;
  }
  for (int a = 0; a < agents; a += 7) crowd[a].x = (a % 2 ? -4.0f : 4.0f) - 0.25f;  // straddling the cuts
  CrowdMetrics whole;
  std::vector<CrowdMetrics> part(ranks), blind(ranks);
  const float reach = static_cast<float>(whole.pair_reach_m()) + 2.0f * 0.3f + 1.0f;
  std::vector<std::vector<AgentObservation>> owned(ranks);
  for (int f = 0; f < frames; ++f) {
    for (auto& o : owned) o.clear();
    for (int a = 0; a < agents; ++a) {
      AgentObservation& o = crowd[a];
      const int owner = partition.owner(o.x, o.z);  // the cut made from where they stood before this step
      o.x += (a % 2 ? 0.02f : 0.03f) * std::sin(0.1f * static_cast<float>(f + a));
      o.z += 0.02f;
      o.arrived = (a % 5 == 0 && f >= 20 + a % 30) ? 1u : 0u;
      o.since_progress = (a % 11 == 0) ? dt * static_cast<float>(f) * 6.0f : 0.0f;  // stuck from frame 25 on
      o.nonfinite = 0;
      AgentObservation seen = o;
      if (a == 37 && f == 30) seen.x = NAN, seen.nonfinite = 1;
      owned[static_cast<std::size_t>(owner < 0 ? 0 : owner)].push_back(seen);
    }
    std::vector<AgentObservation> everyone;
    for (const auto& o : owned) everyone.insert(everyone.end(), o.begin(), o.end());
    whole.observe(everyone, dt);
    std::vector<std::vector<std::uint8_t>> inbox(ranks);
    for (int r = 0; r < ranks; ++r) {
      const auto to_rank = pack_border_observations(owned[r], partition, r, reach);
      for (int k = 0; k < ranks; ++k) inbox[k].insert(inbox[k].end(), to_rank[k].begin(), to_rank[k].end());
    }
    for (int r = 0; r < ranks; ++r) {
      std::vector<AgentObservation> border;
      unpack_border_observations(inbox[r], border);
      part[r].observe(owned[r], border, dt);
      blind[r].observe(owned[r], {}, dt);
    }
  }
  const auto merged = [&](std::vector<CrowdMetrics>& pieces) {
    for (int r = 1; r < ranks; ++r) pieces[0].merge(pieces[r].pack());
    return pieces[0].report();
  };
  const CrowdMetricsReport a = whole.report(), b = merged(part), c = merged(blind);
  EXPECT_GT(a.overlaps, 0u);
  EXPECT_GT(a.stuck_agents, 0u);
  EXPECT_GT(a.reached_goal_pct, 0.0);
  EXPECT_EQ(a.nan_count, 1u);
  EXPECT_EQ(b.agents, a.agents);
  EXPECT_EQ(b.frames, a.frames);
  EXPECT_EQ(b.overlaps, a.overlaps);
  EXPECT_EQ(b.min_clearance_m, a.min_clearance_m);
  EXPECT_EQ(b.reached_goal_pct, a.reached_goal_pct);
  EXPECT_EQ(b.time_to_goal_mean_s, a.time_to_goal_mean_s);
  EXPECT_EQ(b.time_to_goal_p95_s, a.time_to_goal_p95_s);
  EXPECT_EQ(b.stuck_agents, a.stuck_agents);
  EXPECT_EQ(b.nan_count, a.nan_count);
  EXPECT_LT(c.overlaps, a.overlaps) << "pairs across the cuts need the border observations";

  CrowdMetrics other;
  EXPECT_THROW(other.merge(part[1].pack()), std::runtime_error) << "metrics of another number of steps";
  std::vector<std::uint8_t> cut = part[1].pack();
  cut.pop_back();
  EXPECT_THROW(part[0].merge(cut), std::runtime_error);
  std::vector<AgentObservation> out;
  const std::vector<std::uint8_t> odd(17);
  EXPECT_THROW(unpack_border_observations(odd, out), std::runtime_error);
  std::vector<std::uint8_t> nan_bytes(16, 0);
  const float nan = NAN;
  std::memcpy(nan_bytes.data() + 4, &nan, 4);
  EXPECT_THROW(unpack_border_observations(nan_bytes, out), std::runtime_error);
  EXPECT_TRUE(out.empty());
}

TEST(AgentExchange, PlanBudgetGoesToTheWholeCrowdsMostUrgent) {
  // Three processes' offers; the crowd's three most urgent are walkers 7 (no path), then 2 and 4 (a three-way tie
  // at 2 s overdue, broken by the entity index: 2 < 4 < 9, so 9 waits).
  const std::vector<PlanCandidate> a = {{1e9f, 7, 0, 0}, {0.5f, 1, 0, 1}}, b = {{2.0f, 9, 0, 0}, {2.0f, 4, 0, 1}},
                                   c = {{2.0f, 2, 0, 0}};
  std::vector<std::uint8_t> offers;
  for (const auto* mine : {&a, &b, &c}) {
    const std::vector<std::uint8_t> bytes = pack_plan_offers(*mine);
    offers.insert(offers.end(), bytes.begin(), bytes.end());
  }
  std::vector<PlanCandidate> ka = a, kb = b, kc = c;
  keep_most_urgent(ka, offers, 3);
  keep_most_urgent(kb, offers, 3);
  keep_most_urgent(kc, offers, 3);
  ASSERT_EQ(ka.size(), 1u);
  EXPECT_EQ(ka[0].walker, 7u);
  ASSERT_EQ(kb.size(), 1u);
  EXPECT_EQ(kb[0].walker, 4u);
  ASSERT_EQ(kc.size(), 1u);
  EXPECT_EQ(kc[0].walker, 2u);
  offers.pop_back();
  EXPECT_THROW(keep_most_urgent(ka, offers, 3), std::runtime_error);
}

// `ranks` threads, each a process of a distributed run, trading bytes as MpiWorld::exchange does: each sends one
// buffer to every rank and receives what every rank sent it, concatenated in rank order.
class ThreadedRanks {
 public:
  explicit ThreadedRanks(int ranks)
      : ranks_(ranks), sync_(ranks), mail_(static_cast<std::size_t>(ranks), std::vector<std::vector<std::uint8_t>>(static_cast<std::size_t>(ranks))) {}
  std::vector<std::uint8_t> exchange(int me, const std::vector<std::vector<std::uint8_t>>& to_rank) {
    for (int r = 0; r < ranks_; ++r) mail_[static_cast<std::size_t>(r)][static_cast<std::size_t>(me)] = to_rank[static_cast<std::size_t>(r)];
    sync_.arrive_and_wait();
    std::vector<std::uint8_t> out;
    for (const std::vector<std::uint8_t>& from : mail_[static_cast<std::size_t>(me)]) out.insert(out.end(), from.begin(), from.end());
    sync_.arrive_and_wait();  // every rank has read its mail before anyone writes the next round's
    return out;
  }
  std::vector<std::uint8_t> all_gather(int me, const std::vector<std::uint8_t>& mine) {
    return exchange(me, std::vector<std::vector<std::uint8_t>>(static_cast<std::size_t>(ranks_), mine));
  }

 private:
  int ranks_;
  std::barrier<> sync_;
  std::vector<std::vector<std::vector<std::uint8_t>>> mail_;  // [to][from]
};

struct ThreadedAgents final : AgentExchange {
  ThreadedRanks& hub;
  int rank;
  const CrowdPartition& partition;
  float reach;
  std::size_t ghosts = 0;
  ThreadedAgents(ThreadedRanks& h, int r, const CrowdPartition& p, float g) : hub(h), rank(r), partition(p), reach(g) {}
  void exchange_ghosts(std::span<const AgentSnapshot> mine, std::vector<AgentSnapshot>& out) override {
    const std::size_t before = out.size();
    unpack_ghosts(hub.exchange(rank, pack_ghosts(mine, partition, rank, reach)), out);
    ghosts += out.size() - before;
  }
  void select_plans(std::vector<PlanCandidate>& mine, std::size_t take) override {
    keep_most_urgent(mine, hub.all_gather(rank, pack_plan_offers(mine)), take);
  }
};

// A scenario's steered agents over `ranks` threads, each holding and steering only its slab's agents (ghosts and
// plan offers exchanged every step, walkers migrating, slabs recut every second): every agent's state at the end
// equals one crowd's.
TEST(AgentExchange, SteeredAgentsOverRanksMatchOneCrowd) {
  constexpr int kRanks = 3, kFrames = 75;
  const Scenario scenario = shipped_scenario("crossing");
  const auto make = [&] {
    auto crowd = std::make_unique<Crowd>(to_rig(load_default_humanoid()));
    set_detail_level(*crowd, DetailLevel::none());
    ScenarioSetup setup;
    setup.use_cache = false;
    setup.agents = 48;
    set_scenario(*crowd, scenario, setup);
    return crowd;
  };
  auto single = make();
  std::vector<std::unique_ptr<Crowd>> parts;
  for (int r = 0; r < kRanks; ++r) parts.push_back(make());
  const float dt = 1.0f / 30.0f;
  ThreadedRanks hub(kRanks);
  std::vector<CrowdPartition> partitions(kRanks);  // each rank's copy, as each process has its own
  std::vector<std::size_t> ghosts(kRanks), migrated(kRanks);
  std::vector<std::thread> threads;
  for (int r = 0; r < kRanks; ++r)
    threads.emplace_back([&, r] {
      try {
        Crowd& crowd = *parts[static_cast<std::size_t>(r)];
        CrowdPartition& partition = partitions[static_cast<std::size_t>(r)];
        auto agents = std::make_shared<ThreadedAgents>(hub, r, partition, ghost_reach(crowd.agents->avoidance));
        crowd.agents->exchange = agents;
        Profiler profiler(4, false);
        for (int f = 0; f < kFrames; ++f) {
          if (f % 30 == 0) {
            // As apps/crowd_distributed.cpp: the exact cut at the start, where every rank holds every walker; then
            // every rank's histogram over a common box, summed.
            std::vector<float> xs, zs;
            held_placements(crowd, xs, zs);
            if (f == 0) {
              partition = partition_by_density(xs, zs, kRanks);
            } else {
              const PlacementHistogram mine = placement_histogram(xs, zs, -60.0f, 60.0f, -60.0f, 60.0f);
              std::vector<std::uint8_t> bytes(2 * kPartitionBins * 4);
              std::memcpy(bytes.data(), mine.x.data(), kPartitionBins * 4);
              std::memcpy(bytes.data() + kPartitionBins * 4, mine.z.data(), kPartitionBins * 4);
              const std::vector<std::uint8_t> all = hub.all_gather(r, bytes);
              PlacementHistogram sum = placement_histogram({}, {}, -60.0f, 60.0f, -60.0f, 60.0f);
              for (std::size_t at = 0; at < all.size(); at += bytes.size())
                for (std::size_t b = 0; b < kPartitionBins; ++b) {
                  std::uint32_t cx, cz;
                  std::memcpy(&cx, all.data() + at + 4 * b, 4);
                  std::memcpy(&cz, all.data() + at + 4 * (kPartitionBins + b), 4);
                  sum.x[b] += cx, sum.z[b] += cz;
                }
              partition = partition_from_histogram(sum, kRanks);
            }
          }
          if (f == 0) {
            keep_owned(crowd, partition, r);
          } else {
            std::size_t leaving = 0;
            const auto to_rank = pack_leaving(crowd, partition, r, leaving);
            migrated[static_cast<std::size_t>(r)] += leaving;
            unpack_walkers(crowd, hub.exchange(r, to_rank));
          }
          crowd.lod.ownership = partition.region(r);
          step(crowd, dt, profiler);
        }
        ghosts[static_cast<std::size_t>(r)] = agents->ghosts;
      } catch (const std::exception& e) {
        // A failing rank would leave the others waiting at the barrier: end the test process loudly instead.
        std::fprintf(stderr, "rank %d: %s\n", r, e.what());
        std::abort();
      }
    });
  Profiler profiler(4, false);
  for (int f = 0; f < kFrames; ++f) step(*single, dt, profiler);
  for (std::thread& t : threads) t.join();
  const std::vector<Entity> walkers = single->world.entities();
  ASSERT_EQ(walkers.size(), 48u);
  for (std::size_t i = 0; i < walkers.size(); ++i) {
    int holders = 0;
    for (const auto& part : parts) {
      if (part->is_remote(walkers[i])) continue;
      ++holders;
      EXPECT_EQ(walker_state_digest(*part, walkers[i]), walker_state_digest(*single, walkers[i])) << "agent " << i;
    }
    EXPECT_EQ(holders, 1) << "agent " << i;
  }
  std::size_t all_ghosts = 0, all_migrated = 0;
  for (int r = 0; r < kRanks; ++r) all_ghosts += ghosts[static_cast<std::size_t>(r)], all_migrated += migrated[static_cast<std::size_t>(r)];
  EXPECT_GT(all_ghosts, 0u) << "agents met across a border, so the ghosts were tested";
  EXPECT_GT(all_migrated, 0u) << "agents crossed a border, so migration with agents was tested";
}

// The default walking crowd over `ranks` crowds, each holding and animating only its slab's walkers (the rest in
// its remote table; recut every `recut_frames` from every crowd's held placements), against one crowd animating
// everything: every walker's digest at the end equals the single crowd's, from the one crowd that holds it. The
// bytes move between the crowds here as MPI moves them between processes (apps/crowd_distributed.cpp).
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
  std::size_t migrated = 0;
  for (int f = 0; f < frames; ++f) {
    if (f % recut_frames == 0) {
      // At the start every crowd is whole, so one crowd's placements are everyone's; later each holds its own.
      std::vector<float> xs, zs;
      for (int r = 0; r < (f == 0 ? 1 : ranks); ++r) held_placements(*parts[static_cast<std::size_t>(r)], xs, zs);
      ASSERT_EQ(xs.size(), single->walker_count()) << "frame " << f << ": every walker held exactly once";
      partition = partition_by_density(xs, zs, ranks);
    }
    if (f == 0) {
      for (int r = 0; r < ranks; ++r) keep_owned(*parts[static_cast<std::size_t>(r)], partition, r);
    } else {
      std::vector<std::vector<std::uint8_t>> inbox(static_cast<std::size_t>(ranks));
      for (int r = 0; r < ranks; ++r) {
        std::size_t leaving = 0;
        const auto to_rank = pack_leaving(*parts[static_cast<std::size_t>(r)], partition, r, leaving);
        ASSERT_TRUE(to_rank[static_cast<std::size_t>(r)].empty());
        migrated += leaving;
        for (int d = 0; d < ranks; ++d)
          inbox[static_cast<std::size_t>(d)].insert(inbox[static_cast<std::size_t>(d)].end(),
                                                    to_rank[static_cast<std::size_t>(d)].begin(),
                                                    to_rank[static_cast<std::size_t>(d)].end());
      }
      for (int r = 0; r < ranks; ++r) unpack_walkers(*parts[static_cast<std::size_t>(r)], inbox[static_cast<std::size_t>(r)]);
    }
    for (int r = 0; r < ranks; ++r) {
      parts[static_cast<std::size_t>(r)]->lod.ownership = partition.region(r);
      step(*parts[static_cast<std::size_t>(r)], dt, profiler);
    }
    step(*single, dt, profiler);
  }
  const std::vector<Entity> walkers = single->world.entities();
  for (std::size_t i = 0; i < walkers.size(); ++i) {
    int holders = 0;
    for (const auto& part : parts) {
      if (part->is_remote(walkers[i])) continue;
      ++holders;
      EXPECT_EQ(walker_state_digest(*part, walkers[i]), walker_state_digest(*single, walkers[i])) << "walker " << i;
    }
    EXPECT_EQ(holders, 1) << "walker " << i << " is held by exactly one crowd, remote in the others";
  }
  for (const auto& part : parts) EXPECT_TRUE(is_light_walker_table(part->world.table(part->remote_table)));
  EXPECT_GT(migrated, 0u) << "the run must move some walkers across a border to test anything";
}

TEST(PartitionedCrowd, EveryWalkerMatchesOneProcessAcrossBorderCrossings) {
  expect_partitioned_crowd_matches(2, 90, 1000);  // fixed slabs: walkers on the track cross the cut
  expect_partitioned_crowd_matches(3, 60, 15);    // recut every half second
}

}  // namespace
}  // namespace strata
