#include "ecs/world.h"

#include <cstring>
#include <stdexcept>

namespace strata {

std::uint32_t World::add_table(std::unique_ptr<SoaTable> table) {
  if (!table) throw std::invalid_argument("World::add_table: null table");
  tables_.push_back(std::move(table));
  return static_cast<std::uint32_t>(tables_.size() - 1);
}

Entity World::create(std::uint32_t table_id) {
  SoaTable& target = table(table_id);  // throws on a bad id before anything changes
  std::uint32_t slot_index;
  if (!free_slots_.empty()) {
    slot_index = free_slots_.back();
    free_slots_.pop_back();
  } else {
    slot_index = static_cast<std::uint32_t>(slots_.size());
    slots_.push_back(Slot{});
  }
  Slot& slot = slots_[slot_index];
  Entity entity{slot_index + 1, slot.generation};
  slot.alive = true;
  slot.location = {table_id, target.add(entity)};
  ++alive_count_;
  return entity;
}

bool World::alive(Entity entity) const {
  if (entity.is_null() || entity.index > slots_.size()) return false;
  const Slot& slot = slots_[entity.index - 1];
  return slot.alive && slot.generation == entity.generation;
}

EntityLocation World::location(Entity entity) const {
  if (!alive(entity)) throw std::invalid_argument("World::location: dead or null entity");
  return slots_[entity.index - 1].location;
}

bool World::destroy(Entity entity) {
  if (!alive(entity)) return false;
  Slot& slot = slots_[entity.index - 1];
  Entity moved = tables_[slot.location.table]->remove(slot.location.block);
  if (moved) slots_[moved.index - 1].location.block = slot.location.block;
  slot.alive = false;
  // Generation 0 is never issued, so wrap-around (after 4 billion reuses of one slot) skips it.
  if (++slot.generation == 0) slot.generation = 1;
  free_slots_.push_back(entity.index - 1);
  --alive_count_;
  return true;
}

void World::move(Entity entity, std::uint32_t to_table) {
  EntityLocation from = location(entity);
  if (from.table == to_table) return;
  SoaTable& src = *tables_[from.table];
  SoaTable& dst = table(to_table);
  if (src.rows_per_entity() != dst.rows_per_entity())
    throw std::invalid_argument("World::move: tables '" + src.name() + "' and '" + dst.name() +
                                "' have different rows per entity");
  std::uint32_t new_block = dst.add(entity);
  std::size_t rows = src.rows_per_entity();
  for (std::size_t f = 0; f < dst.fields().size(); ++f) {
    const FieldDesc& field = dst.fields()[f];
    std::size_t sf = 0;
    bool found = false;
    for (; sf < src.fields().size(); ++sf)
      if (src.fields()[sf].name == field.name && src.fields()[sf].width == field.width &&
          src.fields()[sf].type == field.type) {
        found = true;
        break;
      }
    if (!found) continue;
    for (std::uint32_t c = 0; c < field.width; ++c) {
      // Same 32-bit storage for every scalar type: copy through the float view when float, else the int one.
      if (field.type == ScalarType::F32)
        std::memcpy(dst.f32(f, c).data() + new_block * rows, src.f32(sf, c).data() + from.block * rows,
                    rows * sizeof(float));
      else if (field.type == ScalarType::I32)
        std::memcpy(dst.i32(f, c).data() + new_block * rows, src.i32(sf, c).data() + from.block * rows,
                    rows * sizeof(std::int32_t));
      else
        std::memcpy(dst.u32(f, c).data() + new_block * rows, src.u32(sf, c).data() + from.block * rows,
                    rows * sizeof(std::uint32_t));
    }
  }
  Entity moved = src.remove(from.block);
  if (moved) slots_[moved.index - 1].location.block = from.block;
  slots_[entity.index - 1].location = {to_table, new_block};
}

std::vector<Entity> World::entities() const {
  std::vector<Entity> out;
  out.reserve(alive_count_);
  for (std::size_t i = 0; i < slots_.size(); ++i)
    if (slots_[i].alive) out.push_back(Entity{static_cast<std::uint32_t>(i + 1), slots_[i].generation});
  return out;
}

std::vector<std::string> World::validate() const {
  std::vector<std::string> problems;
  auto describe = [](Entity e) {
    return "entity{" + std::to_string(e.index) + "," + std::to_string(e.generation) + "}";
  };
  std::size_t alive_seen = 0;
  for (std::uint32_t i = 0; i < slots_.size(); ++i) {
    const Slot& slot = slots_[i];
    if (slot.generation == 0) problems.push_back("slot " + std::to_string(i) + " has generation 0");
    if (!slot.alive) continue;
    ++alive_seen;
    Entity e{i + 1, slot.generation};
    if (slot.location.table >= tables_.size()) {
      problems.push_back(describe(e) + " points at missing table " + std::to_string(slot.location.table));
      continue;
    }
    const SoaTable& t = *tables_[slot.location.table];
    if (slot.location.block >= t.size())
      problems.push_back(describe(e) + " points past the end of table '" + t.name() + "'");
    else if (t.owner(slot.location.block) != e)
      problems.push_back(describe(e) + " is not the owner of its block " + std::to_string(slot.location.block) +
                         " in table '" + t.name() + "'");
  }
  if (alive_seen != alive_count_)
    problems.push_back("alive count " + std::to_string(alive_count_) + " but " + std::to_string(alive_seen) +
                       " live slots");
  std::size_t rows_total = 0;
  for (std::uint32_t t = 0; t < tables_.size(); ++t) {
    const SoaTable& table = *tables_[t];
    rows_total += table.size();
    for (std::uint32_t b = 0; b < table.size(); ++b) {
      Entity owner = table.owner(b);
      if (!alive(owner)) {
        problems.push_back("table '" + table.name() + "' block " + std::to_string(b) + " owned by dead " +
                           describe(owner));
        continue;
      }
      EntityLocation loc = slots_[owner.index - 1].location;
      if (loc.table != t || loc.block != b)
        problems.push_back("table '" + table.name() + "' block " + std::to_string(b) + ": owner " +
                           describe(owner) + " points elsewhere");
    }
  }
  if (rows_total != alive_count_)
    problems.push_back("tables hold " + std::to_string(rows_total) + " blocks for " + std::to_string(alive_count_) +
                       " live entities");
  std::vector<bool> seen_free(slots_.size(), false);
  for (std::uint32_t s : free_slots_) {
    if (s >= slots_.size()) {
      problems.push_back("free list holds out-of-range slot " + std::to_string(s));
      continue;
    }
    if (slots_[s].alive) problems.push_back("free list holds live slot " + std::to_string(s));
    if (seen_free[s]) problems.push_back("free list holds slot " + std::to_string(s) + " twice");
    seen_free[s] = true;
  }
  if (free_slots_.size() + alive_count_ != slots_.size())
    problems.push_back("free list size does not match dead slots");
  return problems;
}

}  // namespace strata
