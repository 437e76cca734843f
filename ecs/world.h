#pragma once
// World: the entity pool plus the tables entities live in. An entity is a walker; where it lives (table and
// block) is its state, in the Box2D/flecs manner: moving it between tables changes what systems see it, so hot
// loops never test flags.
//
// Handles are checked in one place (alive()). Destroying an entity swap-removes its block and patches the moved
// entity's location, which validate() re-derives from scratch in tests and debug runs.
#include <memory>
#include <string>
#include <vector>

#include "ecs/entity.h"
#include "ecs/soa_table.h"

namespace strata {

struct EntityLocation {
  std::uint32_t table = 0;
  std::uint32_t block = 0;
};

class World {
 public:
  // Adds a table; returns its id (index). Tables are never removed, so ids stay valid.
  std::uint32_t add_table(std::unique_ptr<SoaTable> table);
  SoaTable& table(std::uint32_t id) { return *tables_.at(id); }
  const SoaTable& table(std::uint32_t id) const { return *tables_.at(id); }
  std::size_t table_count() const { return tables_.size(); }

  Entity create(std::uint32_t table_id);
  // Returns false (and changes nothing) for a null, stale or never-issued handle.
  bool destroy(Entity entity);
  bool alive(Entity entity) const;
  // Location of a live entity; throws std::invalid_argument for a dead or null one.
  EntityLocation location(Entity entity) const;
  // Moves a live entity to another table, copying the fields both tables share by name and width.
  void move(Entity entity, std::uint32_t to_table);
  std::size_t alive_count() const { return alive_count_; }
  // Every live entity in slot order: the order they were created in, for a world whose entities were never
  // destroyed. A canonical order for hashes and reports, whatever tables the entities have moved through.
  std::vector<Entity> entities() const;

  // Re-derives every invariant (pool <-> tables back-pointers, free list, counts). Returns a description of each
  // violation; empty means consistent. O(entities); meant for tests and a --validate switch.
  std::vector<std::string> validate() const;

 private:
  struct Slot {
    std::uint32_t generation = 1;  // generation of the current or next occupant; starts at 1 so {i,0} is stale
    bool alive = false;
    EntityLocation location;
  };
  std::vector<Slot> slots_;
  std::vector<std::uint32_t> free_slots_;  // LIFO free list of slot indices (0-based)
  std::vector<std::unique_ptr<SoaTable>> tables_;
  std::size_t alive_count_ = 0;
};

}  // namespace strata
