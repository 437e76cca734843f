#include "dist/partition.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace strata {

OwnershipRegion CrowdPartition::region(int rank) const {
  if (rank < 0 || rank >= ranks()) throw std::out_of_range("CrowdPartition::region: no rank " + std::to_string(rank));
  OwnershipRegion r;
  r.axis = axis;
  const auto k = static_cast<std::size_t>(rank);
  r.lo = rank == 0 ? -std::numeric_limits<float>::infinity() : cuts[k - 1];
  r.hi = k == cuts.size() ? std::numeric_limits<float>::infinity() : cuts[k];
  return r;
}

int CrowdPartition::owner(float x, float z) const {
  const float c = axis == 0 ? x : z;
  if (!std::isfinite(c)) return -1;
  // The first cut above c: slab k holds [cut[k-1], cut[k]).
  return static_cast<int>(std::upper_bound(cuts.begin(), cuts.end(), c) - cuts.begin());
}

CrowdPartition partition_by_density(std::span<const float> xs, std::span<const float> zs, int ranks) {
  if (ranks < 1) throw std::invalid_argument("partition_by_density: ranks must be at least 1");
  if (xs.size() != zs.size()) throw std::invalid_argument("partition_by_density: xs and zs differ in size");
  CrowdPartition p;
  p.cuts.assign(static_cast<std::size_t>(ranks - 1), 0.0f);
  float lo_x = std::numeric_limits<float>::max(), hi_x = std::numeric_limits<float>::lowest();
  float lo_z = lo_x, hi_z = hi_x;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    if (!std::isfinite(xs[i]) || !std::isfinite(zs[i])) continue;
    lo_x = std::min(lo_x, xs[i]), hi_x = std::max(hi_x, xs[i]);
    lo_z = std::min(lo_z, zs[i]), hi_z = std::max(hi_z, zs[i]);
  }
  if (lo_x > hi_x) return p;  // no walker placed
  p.axis = hi_z - lo_z > hi_x - lo_x ? 2 : 0;
  std::vector<float> c;
  c.reserve(xs.size());
  for (std::size_t i = 0; i < xs.size(); ++i)
    if (std::isfinite(xs[i]) && std::isfinite(zs[i])) c.push_back(p.axis == 0 ? xs[i] : zs[i]);
  std::sort(c.begin(), c.end());
  const std::size_t n = c.size();
  for (int k = 1; k < ranks; ++k) {
    const std::size_t at = n * static_cast<std::size_t>(k) / static_cast<std::size_t>(ranks);
    float cut;
    if (at == 0) cut = c.front();
    else if (at >= n) cut = std::nextafter(c.back(), std::numeric_limits<float>::infinity());
    else cut = 0.5f * (c[at - 1] + c[at]);
    // Cuts never decrease (several quantiles may fall between the same two walkers).
    p.cuts[static_cast<std::size_t>(k - 1)] = k > 1 ? std::max(cut, p.cuts[static_cast<std::size_t>(k - 2)]) : cut;
  }
  return p;
}

namespace {

std::size_t bin_of(float c, float lo, float hi) {
  if (!(hi > lo)) return 0;
  const double f = (static_cast<double>(c) - lo) / (static_cast<double>(hi) - lo);
  return std::min(kPartitionBins - 1, static_cast<std::size_t>(std::max(0.0, f * static_cast<double>(kPartitionBins))));
}

}  // namespace

PlacementHistogram placement_histogram(std::span<const float> xs, std::span<const float> zs, float lo_x, float hi_x,
                                       float lo_z, float hi_z) {
  if (xs.size() != zs.size()) throw std::invalid_argument("placement_histogram: xs and zs differ in size");
  PlacementHistogram h{lo_x, hi_x, lo_z, hi_z, std::vector<std::uint32_t>(kPartitionBins, 0),
                       std::vector<std::uint32_t>(kPartitionBins, 0)};
  for (std::size_t i = 0; i < xs.size(); ++i) {
    if (!std::isfinite(xs[i]) || !std::isfinite(zs[i])) continue;
    ++h.x[bin_of(xs[i], lo_x, hi_x)];
    ++h.z[bin_of(zs[i], lo_z, hi_z)];
  }
  return h;
}

CrowdPartition partition_from_histogram(const PlacementHistogram& h, int ranks) {
  if (ranks < 1) throw std::invalid_argument("partition_from_histogram: ranks must be at least 1");
  if (h.x.size() != kPartitionBins || h.z.size() != kPartitionBins)
    throw std::invalid_argument("partition_from_histogram: a histogram of " + std::to_string(kPartitionBins) + " bins an axis");
  CrowdPartition p;
  p.cuts.assign(static_cast<std::size_t>(ranks - 1), 0.0f);
  p.axis = h.hi_z - h.lo_z > h.hi_x - h.lo_x ? 2 : 0;
  const std::vector<std::uint32_t>& bins = p.axis == 0 ? h.x : h.z;
  const double lo = p.axis == 0 ? h.lo_x : h.lo_z, hi = p.axis == 0 ? h.hi_x : h.hi_z;
  const double width = (hi - lo) / static_cast<double>(kPartitionBins);
  std::uint64_t n = 0;
  for (const std::uint32_t c : bins) n += c;
  if (n == 0) return p;
  std::size_t bin = 0;
  std::uint64_t below = 0;  // walkers in the bins before `bin`
  for (int k = 1; k < ranks; ++k) {
    const double want = static_cast<double>(n) * k / ranks;
    while (bin + 1 < kPartitionBins && static_cast<double>(below + bins[bin]) < want) below += bins[bin++];
    const double inside = bins[bin] > 0 ? (want - static_cast<double>(below)) / bins[bin] : 0.0;
    const auto cut = static_cast<float>(lo + width * (static_cast<double>(bin) + std::clamp(inside, 0.0, 1.0)));
    p.cuts[static_cast<std::size_t>(k - 1)] = k > 1 ? std::max(cut, p.cuts[static_cast<std::size_t>(k - 2)]) : cut;
  }
  return p;
}

std::vector<std::size_t> walkers_per_rank(const CrowdPartition& partition, std::span<const float> xs,
                                          std::span<const float> zs) {
  std::vector<std::size_t> n(static_cast<std::size_t>(partition.ranks()), 0);
  for (std::size_t i = 0; i < xs.size() && i < zs.size(); ++i)
    if (const int r = partition.owner(xs[i], zs[i]); r >= 0) ++n[static_cast<std::size_t>(r)];
  return n;
}

}  // namespace strata
