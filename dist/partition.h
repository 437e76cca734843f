#pragma once
// How one crowd is cut between processes: slabs of ground along its longer axis, each holding about the same
// number of walkers (a k-d split's first level, repeated K-1 times along one axis). Every process computes the
// cuts itself from the placements every process advances identically (systems/ownership.h), so a rebalance sends
// no bytes and all processes agree on every walker's owner.
//
// Rejected: a full k-d tree alternating axes. For the crowds here (lanes, a plaza, a corridor) slabs across the
// longer axis give borders as short as a k-d split for K <= 4 and keep a walker's owner a function of one
// coordinate; the border-length scaling holds for either.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "systems/ownership.h"

namespace strata {

struct CrowdPartition {
  int axis = 0;             // 0: x, 2: z
  std::vector<float> cuts;  // ranks - 1 ascending cut positions along `axis`
  int ranks() const { return static_cast<int>(cuts.size()) + 1; }
  // The slab of `rank`: [cut[rank-1], cut[rank]), the end slabs open to infinity.
  OwnershipRegion region(int rank) const;
  // The rank whose slab holds (x, z); -1 for a non-finite coordinate.
  int owner(float x, float z) const;
};

// Cuts for `ranks` slabs from walker positions (xs[i], zs[i]): the axis with the larger extent, each cut halfway
// between the two walkers on either side of a 1/ranks quantile. Non-finite positions are ignored; with no
// walkers the cuts are 0. Deterministic: a function of the multiset of positions only.
CrowdPartition partition_by_density(std::span<const float> xs, std::span<const float> zs, int ranks);

// Recuts when each process holds only its own walkers: every process counts its walkers' placements into a
// histogram along both axes over the box of all of them (MpiWorld::min_max), the histograms are summed over the
// processes (MpiWorld::sum), and every process cuts the same sum. A recut then costs each process the histogram's
// bytes (2 x kPartitionBins counts), whatever the crowd's size; sending every placement to every process (12
// bytes a walker) was rejected for growing with the crowd. Cuts fall on bin edges, interpolated within the bin
// that holds a quantile, so slabs balance to within one bin's walkers (a bin is 1/1024 of the crowd's extent).
inline constexpr std::size_t kPartitionBins = 1024;
struct PlacementHistogram {
  float lo_x = 0, hi_x = 0, lo_z = 0, hi_z = 0;  // the box every process uses
  std::vector<std::uint32_t> x, z;              // kPartitionBins counts along each axis
};
// A histogram over the box [lo_x, hi_x] x [lo_z, hi_z] holding the finite placements (xs[i], zs[i]) inside it.
PlacementHistogram placement_histogram(std::span<const float> xs, std::span<const float> zs, float lo_x, float hi_x,
                                       float lo_z, float hi_z);
// Cuts for `ranks` slabs from a (summed) histogram: the axis with the larger extent, cut k where the cumulative
// count reaches k/ranks of the walkers. Deterministic: a function of the histogram only.
CrowdPartition partition_from_histogram(const PlacementHistogram& histogram, int ranks);

// Walkers per rank under `partition` (for the load report).
std::vector<std::size_t> walkers_per_rank(const CrowdPartition& partition, std::span<const float> xs,
                                          std::span<const float> zs);

}  // namespace strata
