#include "dist/migration.h"

#include <cstring>
#include <stdexcept>
#include <string>

namespace strata {
namespace {

struct WalkerHeader {
  std::uint32_t index, generation;
  std::uint32_t slot_and_count;  // slot in the top 8 bits, row scalars in the low 24
};
static_assert(sizeof(WalkerHeader) == 12);

}  // namespace

void pack_walkers(const Crowd& crowd, std::span<const Entity> walkers, std::vector<std::uint8_t>& out) {
  std::vector<std::uint32_t> row;
  for (const Entity w : walkers) {
    const EntityLocation at = crowd.world.location(w);
    const SoaTable& t = crowd.world.table(at.table);
    const std::size_t n = t.block_scalars();
    if (n >= (1u << 24)) throw std::logic_error("pack_walkers: a walker row of more than 2^24 scalars");
    row.resize(n);
    t.read_block(at.block, row);
    const WalkerHeader h{w.index, w.generation,
                         (static_cast<std::uint32_t>(slot_index(crowd.slot_of(w))) << 24) | static_cast<std::uint32_t>(n)};
    const std::size_t at_byte = out.size();
    out.resize(at_byte + sizeof h + 4 * n);
    std::memcpy(out.data() + at_byte, &h, sizeof h);
    std::memcpy(out.data() + at_byte + sizeof h, row.data(), 4 * n);
  }
}

std::size_t unpack_walkers(Crowd& crowd, std::span<const std::uint8_t> bytes) {
  // Checked whole first, so malformed input changes nothing.
  struct Item {
    Entity walker;
    DetailSlot slot;
    std::size_t at, scalars;
  };
  std::vector<Item> items;
  for (std::size_t at = 0; at < bytes.size();) {
    WalkerHeader h;
    if (bytes.size() - at < sizeof h) throw std::runtime_error("unpack_walkers: truncated walker header");
    std::memcpy(&h, bytes.data() + at, sizeof h);
    const Entity w{h.index, h.generation};
    const std::uint32_t slot = h.slot_and_count >> 24;
    const std::size_t n = h.slot_and_count & 0xffffffu;
    if (slot >= kDetailSlots) throw std::runtime_error("unpack_walkers: bad slot " + std::to_string(slot));
    if (!crowd.world.alive(w))
      throw std::runtime_error("unpack_walkers: walker " + std::to_string(h.index) + " is not in this crowd");
    if (crowd.table(static_cast<DetailSlot>(slot)).block_scalars() != n)
      throw std::runtime_error("unpack_walkers: walker " + std::to_string(h.index) + "'s row does not fit table " +
                               crowd.table(static_cast<DetailSlot>(slot)).name());
    if ((bytes.size() - at - sizeof h) / 4 < n) throw std::runtime_error("unpack_walkers: truncated walker row");
    items.push_back({w, static_cast<DetailSlot>(slot), at + sizeof h, n});
    at += sizeof h + 4 * n;
  }
  std::vector<std::uint32_t> row;
  for (const Item& item : items) {
    crowd.world.move(item.walker, crowd.tables[slot_index(item.slot)]);
    const EntityLocation at = crowd.world.location(item.walker);
    row.resize(item.scalars);
    std::memcpy(row.data(), bytes.data() + item.at, 4 * item.scalars);
    crowd.world.table(at.table).write_block(at.block, row);
  }
  return items.size();
}

namespace {

// Calls f(walker, x, z) for every held walker, table by table.
template <class F>
void for_each_held(const Crowd& crowd, F&& f) {
  for (std::size_t s = 0; s < kDetailSlots; ++s) {
    const SoaTable& t = crowd.world.table(crowd.tables[s]);
    for (std::uint32_t r = 0; r < t.size(); ++r)
      f(t.owner(r), t.f32(kWalkerPlacement, 0)[r], t.f32(kWalkerPlacement, 2)[r]);
  }
}

}  // namespace

std::size_t keep_owned(Crowd& crowd, const CrowdPartition& partition, int rank) {
  std::vector<Entity> others;
  std::size_t owned = 0;
  for_each_held(crowd, [&](Entity w, float x, float z) {
    const int owner = partition.owner(x, z);
    if (owner >= 0 && owner != rank) others.push_back(w);
    owned += owner == rank;
  });
  for (const Entity w : others) crowd.world.move(w, crowd.remote_table);
  return owned;
}

std::vector<std::vector<std::uint8_t>> pack_leaving(Crowd& crowd, const CrowdPartition& partition, int rank,
                                                    std::size_t& leaving) {
  std::vector<std::vector<Entity>> to(static_cast<std::size_t>(partition.ranks()));
  for_each_held(crowd, [&](Entity w, float x, float z) {
    const int owner = partition.owner(x, z);
    if (owner >= 0 && owner != rank) to[static_cast<std::size_t>(owner)].push_back(w);
  });
  std::vector<std::vector<std::uint8_t>> bytes(to.size());
  leaving = 0;
  for (std::size_t r = 0; r < to.size(); ++r) {
    pack_walkers(crowd, to[r], bytes[r]);
    leaving += to[r].size();
  }
  for (const std::vector<Entity>& walkers : to)
    for (const Entity w : walkers) crowd.world.move(w, crowd.remote_table);
  return bytes;
}

void held_placements(const Crowd& crowd, std::vector<float>& xs, std::vector<float>& zs) {
  for_each_held(crowd, [&](Entity, float x, float z) {
    xs.push_back(x);
    zs.push_back(z);
  });
}

}  // namespace strata
