#include "dist/agent_exchange.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

namespace strata {
namespace {

// The wire form of a ghost: the entity index and twelve floats, no padding.
constexpr std::size_t kGhostFloats = 12;
constexpr std::size_t kGhostBytes = 4 + kGhostFloats * 4;
// Of a border observation: the entity index and three floats.
constexpr std::size_t kObservationBytes = 4 + 3 * 4;
// Of a plan offer: urgency and entity index.
constexpr std::size_t kOfferBytes = 4 + 4;

void put(std::vector<std::uint8_t>& out, const void* p, std::size_t n) {
  const auto* b = static_cast<const std::uint8_t*>(p);
  out.insert(out.end(), b, b + n);
}

// Per rank but `rank`, the items whose position along the partition's axis (`x_of`, `z_of`) lies within `reach` of
// that rank's slab, each appended by `write`. (A NaN position is within no reach.)
template <class Item, class X, class Z, class Write>
std::vector<std::vector<std::uint8_t>> pack_near_slabs(std::span<const Item> items, const CrowdPartition& partition,
                                                       int rank, float reach, X x_of, Z z_of, Write write) {
  const int ranks = partition.ranks();
  std::vector<std::vector<std::uint8_t>> to_rank(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r) {
    if (r == rank) continue;
    const OwnershipRegion region = partition.region(r);
    std::vector<std::uint8_t>& out = to_rank[static_cast<std::size_t>(r)];
    for (const Item& item : items) {
      const float c = region.axis == 0 ? x_of(item) : z_of(item);
      if (c >= region.lo - reach && c < region.hi + reach) write(out, item);
    }
  }
  return to_rank;
}

}  // namespace

float ghost_reach(const AvoidanceParameters& params) { return 2.0f * params.neighbor_distance + 1.0f; }

std::vector<std::vector<std::uint8_t>> pack_ghosts(std::span<const AgentSnapshot> mine,
                                                   const CrowdPartition& partition, int rank, float reach) {
  return pack_near_slabs(
      mine, partition, rank, reach, [](const AgentSnapshot& s) { return s.px; },
      [](const AgentSnapshot& s) { return s.pz; },
      [](std::vector<std::uint8_t>& out, const AgentSnapshot& s) {
        const float values[kGhostFloats] = {s.px,     s.pz,        s.vx,        s.vz,         s.pref_vx, s.pref_vz,
                                            s.radius, s.max_speed, s.tether_dx, s.tether_dz, s.tether_reach,
                                            s.holds};
        put(out, &s.walker, 4);
        put(out, values, sizeof values);
      });
}

void unpack_ghosts(std::span<const std::uint8_t> bytes, std::vector<AgentSnapshot>& out) {
  if (bytes.size() % kGhostBytes != 0)
    throw std::runtime_error("unpack_ghosts: " + std::to_string(bytes.size()) + " bytes are not whole agents");
  const std::size_t n = bytes.size() / kGhostBytes;
  const std::size_t start = out.size();
  out.resize(start + n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint8_t* p = bytes.data() + k * kGhostBytes;
    AgentSnapshot& s = out[start + k];
    float v[kGhostFloats];
    std::memcpy(&s.walker, p, 4);
    std::memcpy(v, p + 4, sizeof v);
    const bool finite = std::all_of(std::begin(v), std::end(v), [](float x) { return std::isfinite(x); });
    if (!finite || !(v[6] > 0.0f) || v[7] < 0.0f) {
      out.resize(start);
      throw std::runtime_error("unpack_ghosts: agent " + std::to_string(s.walker) +
                               " has a non-finite value, a radius <= 0 or a negative speed");
    }
    s.px = v[0], s.pz = v[1], s.vx = v[2], s.vz = v[3], s.pref_vx = v[4], s.pref_vz = v[5];
    s.radius = v[6], s.max_speed = v[7];
    s.tether_dx = v[8], s.tether_dz = v[9], s.tether_reach = v[10], s.holds = v[11];
  }
}

std::vector<std::vector<std::uint8_t>> pack_border_observations(std::span<const AgentObservation> mine,
                                                                const CrowdPartition& partition, int rank, float reach) {
  return pack_near_slabs(
      mine, partition, rank, reach, [](const AgentObservation& o) { return o.x; },
      [](const AgentObservation& o) { return o.z; },
      [](std::vector<std::uint8_t>& out, const AgentObservation& o) {
        if (!std::isfinite(o.x + o.z + o.radius)) return;
        const float values[3] = {o.x, o.z, o.radius};
        put(out, &o.walker, 4);
        put(out, values, sizeof values);
      });
}

void unpack_border_observations(std::span<const std::uint8_t> bytes, std::vector<AgentObservation>& out) {
  if (bytes.size() % kObservationBytes != 0)
    throw std::runtime_error("unpack_border_observations: " + std::to_string(bytes.size()) +
                             " bytes are not whole observations");
  const std::size_t n = bytes.size() / kObservationBytes;
  const std::size_t start = out.size();
  out.resize(start + n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint8_t* p = bytes.data() + k * kObservationBytes;
    AgentObservation& o = out[start + k];
    float v[3];
    std::memcpy(&o.walker, p, 4);
    std::memcpy(v, p + 4, sizeof v);
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
      const std::uint32_t walker = o.walker;
      out.resize(start);
      throw std::runtime_error("unpack_border_observations: agent " + std::to_string(walker) + " has a non-finite value");
    }
    o.x = v[0], o.z = v[1], o.radius = v[2];
  }
}

std::vector<std::uint8_t> pack_plan_offers(std::span<const PlanCandidate> mine) {
  std::vector<std::uint8_t> out;
  out.reserve(mine.size() * kOfferBytes);
  for (const PlanCandidate& c : mine) {
    put(out, &c.urgency, 4);
    put(out, &c.walker, 4);
  }
  return out;
}

void keep_most_urgent(std::vector<PlanCandidate>& mine, std::span<const std::uint8_t> offers, std::size_t take) {
  if (offers.size() % kOfferBytes != 0)
    throw std::runtime_error("keep_most_urgent: " + std::to_string(offers.size()) + " bytes are not whole offers");
  std::vector<PlanCandidate> all(offers.size() / kOfferBytes);
  for (std::size_t k = 0; k < all.size(); ++k) {
    std::memcpy(&all[k].urgency, offers.data() + k * kOfferBytes, 4);
    std::memcpy(&all[k].walker, offers.data() + k * kOfferBytes + 4, 4);
    if (std::isnan(all[k].urgency)) throw std::runtime_error("keep_most_urgent: a NaN urgency");
  }
  take = std::min(take, all.size());
  std::partial_sort(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(take), all.end(), more_urgent);
  all.resize(take);
  // The chosen, by entity index, to look up this process's own.
  std::vector<std::uint32_t> chosen;
  chosen.reserve(take);
  for (const PlanCandidate& c : all) chosen.push_back(c.walker);
  std::sort(chosen.begin(), chosen.end());
  std::erase_if(mine, [&](const PlanCandidate& c) { return !std::binary_search(chosen.begin(), chosen.end(), c.walker); });
}

}  // namespace strata
