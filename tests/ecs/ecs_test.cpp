// ECS core: handles, SoA tables, swap-remove back-pointers, checked against a trivial model.
#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <random>
#include <unordered_map>
#include <vector>

#include "ecs/world.h"

namespace strata {
namespace {

std::unique_ptr<SoaTable> make_table(const char* name, std::uint32_t rows_per_entity = 1) {
  return std::make_unique<SoaTable>(name,
                                    std::vector<FieldDesc>{{"pos", ScalarType::F32, 3, 0.0f},
                                                           {"id", ScalarType::U32, 1, 0.0f},
                                                           {"level", ScalarType::I32, 1, -1.0f}},
                                    rows_per_entity);
}

TEST(Entity, ValueInitialisedIsNull) {
  Entity e{};
  EXPECT_TRUE(e.is_null());
  EXPECT_FALSE(static_cast<bool>(e));
  World world;
  EXPECT_FALSE(world.alive(e));
  EXPECT_FALSE(world.destroy(e));
  EXPECT_THROW((void)world.location(e), std::invalid_argument);
}

TEST(Entity, StaleHandleIsDetectedAfterSlotReuse) {
  World world;
  auto t = world.add_table(make_table("t"));
  Entity a = world.create(t);
  EXPECT_TRUE(world.alive(a));
  EXPECT_TRUE(world.destroy(a));
  EXPECT_FALSE(world.alive(a));
  EXPECT_FALSE(world.destroy(a)) << "double destroy must be refused";
  Entity b = world.create(t);
  EXPECT_EQ(b.index, a.index) << "the freed slot is reused";
  EXPECT_NE(b.generation, a.generation);
  EXPECT_FALSE(world.alive(a)) << "old handle to a reused slot is stale";
  EXPECT_TRUE(world.alive(b));
  EXPECT_FALSE(world.alive(Entity{b.index + 7, 1})) << "never-issued index";
  EXPECT_FALSE(world.alive(Entity{b.index, 0})) << "generation 0 is never issued";
}

TEST(SoaTable, ColumnsAreAlignedAndPadded) {
  SoaTable table("t", {{"x", ScalarType::F32, 5, 2.5f}});
  for (int i = 0; i < 37; ++i) table.add(Entity{static_cast<std::uint32_t>(i + 1), 1});
  EXPECT_EQ(table.stride() % kSimdLaneFloats, 0u);
  EXPECT_GE(table.stride(), table.row_count());
  for (std::uint32_t c = 0; c < 5; ++c) {
    auto col = table.f32(0, c);
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(col.data()) % kColumnAlignment, 0u);
    EXPECT_EQ(col.size(), 37u);
    for (float v : col) EXPECT_EQ(v, 2.5f) << "new rows take the field default";
  }
}

TEST(SoaTable, WrongTypeOrComponentIsRejected) {
  SoaTable table("t", {{"x", ScalarType::F32, 2}, {"n", ScalarType::I32, 1}});
  table.add(Entity{1, 1});
  EXPECT_THROW((void)table.i32(0), std::invalid_argument);
  EXPECT_THROW((void)table.f32(1), std::invalid_argument);
  EXPECT_THROW((void)table.f32(0, 2), std::out_of_range);
  EXPECT_THROW((void)table.field_index("nope"), std::out_of_range);
  EXPECT_EQ(table.field_index("n"), 1u);
  EXPECT_THROW(SoaTable("dup", {{"a", ScalarType::F32, 1}, {"a", ScalarType::F32, 1}}), std::invalid_argument);
}

TEST(SoaTable, SwapRemoveMovesLastBlockAndReportsIt) {
  SoaTable table("t", {{"v", ScalarType::F32, 2}}, 3);
  for (std::uint32_t e = 1; e <= 4; ++e) {
    auto b = table.add(Entity{e, 1});
    for (std::uint32_t c = 0; c < 2; ++c)
      for (std::uint32_t r = 0; r < 3; ++r) table.f32(0, c)[b * 3 + r] = float(e * 100 + c * 10 + r);
  }
  Entity moved = table.remove(1);
  EXPECT_EQ(moved, (Entity{4, 1}));
  ASSERT_EQ(table.size(), 3u);
  for (std::uint32_t c = 0; c < 2; ++c)
    for (std::uint32_t r = 0; r < 3; ++r) EXPECT_EQ(table.f32(0, c)[1 * 3 + r], float(400 + c * 10 + r));
  EXPECT_TRUE(table.remove(2).is_null()) << "removing the last block moves nothing";
  EXPECT_THROW(table.remove(5), std::out_of_range);
}

// The model: for every live handle, the values it should see; for every dead one, that it is dead.
struct ModelValue {
  float pos[3];
  std::uint32_t id;
  std::uint32_t table;
};

void check_against_model(const World& world, const std::unordered_map<Entity, ModelValue>& live,
                         const std::vector<Entity>& dead) {
  ASSERT_EQ(world.alive_count(), live.size());
  for (const auto& [e, v] : live) {
    ASSERT_TRUE(world.alive(e));
    EntityLocation loc = world.location(e);
    ASSERT_EQ(loc.table, v.table);
    const SoaTable& t = world.table(loc.table);
    ASSERT_EQ(t.owner(loc.block), e);
    for (std::uint32_t c = 0; c < 3; ++c) ASSERT_EQ(t.f32(0, c)[loc.block], v.pos[c]);
    ASSERT_EQ(t.u32(1)[loc.block], v.id);
  }
  for (Entity e : dead) ASSERT_FALSE(world.alive(e));
  auto problems = world.validate();
  ASSERT_TRUE(problems.empty()) << problems.front();
}

TEST(World, RandomisedOperationsMatchTrivialModel) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    std::mt19937_64 rng(seed);
    World world;
    std::uint32_t tables[2] = {world.add_table(make_table("a")), world.add_table(make_table("b"))};
    std::unordered_map<Entity, ModelValue> live;
    std::vector<Entity> handles;  // live ones, for picking
    std::vector<Entity> dead;
    std::uint32_t next_id = 1;
    for (int step = 0; step < 5000; ++step) {
      unsigned op = rng() % 10;
      if (op < 5 || handles.empty()) {  // create
        std::uint32_t t = tables[rng() % 2];
        Entity e = world.create(t);
        ASSERT_FALSE(world.alive(Entity{}));
        for (Entity d : dead) ASSERT_NE(d, e) << "a handle is never issued twice";
        EntityLocation loc = world.location(e);
        ModelValue v{{float(rng() % 1000), float(rng() % 1000), float(rng() % 1000)}, next_id++, t};
        SoaTable& table = world.table(t);
        EXPECT_EQ(table.i32(2)[loc.block], -1) << "default applies to int fields";
        for (std::uint32_t c = 0; c < 3; ++c) table.f32(0, c)[loc.block] = v.pos[c];
        table.u32(1)[loc.block] = v.id;
        live[e] = v;
        handles.push_back(e);
      } else if (op < 8) {  // destroy a random live one
        std::size_t k = rng() % handles.size();
        Entity e = handles[k];
        ASSERT_TRUE(world.destroy(e));
        live.erase(e);
        handles[k] = handles.back();
        handles.pop_back();
        dead.push_back(e);
      } else if (op < 9) {  // move to the other table
        Entity e = handles[rng() % handles.size()];
        std::uint32_t to = live[e].table == tables[0] ? tables[1] : tables[0];
        world.move(e, to);
        live[e].table = to;
      } else if (!dead.empty()) {  // stale handles must be refused
        Entity e = dead[rng() % dead.size()];
        ASSERT_FALSE(world.destroy(e));
        ASSERT_THROW((void)world.location(e), std::invalid_argument);
      }
      if (step % 97 == 0) check_against_model(world, live, dead);
    }
    check_against_model(world, live, dead);
  }
}

TEST(World, ValidateReportsCorruptedBackPointer) {
  World world;
  auto t = world.add_table(make_table("t"));
  Entity a = world.create(t);
  Entity b = world.create(t);
  ASSERT_TRUE(world.validate().empty());
  // Remove a block behind the world's back: the table now disagrees with the pool.
  world.table(t).remove(world.location(a).block);
  auto problems = world.validate();
  EXPECT_FALSE(problems.empty());
  (void)b;
}

TEST(World, MoveKeepsSharedFieldsAndRejectsDifferentBlockSizes) {
  World world;
  auto a = world.add_table(make_table("a"));
  auto b = world.add_table(std::make_unique<SoaTable>(
      "b", std::vector<FieldDesc>{{"id", ScalarType::U32, 1}, {"extra", ScalarType::F32, 1, 7.0f}}));
  auto c = world.add_table(make_table("c", 4));
  Entity e = world.create(a);
  world.table(a).u32(1)[world.location(e).block] = 42;
  world.move(e, b);
  EXPECT_EQ(world.location(e).table, b);
  EXPECT_EQ(world.table(b).u32(0)[world.location(e).block], 42u);
  EXPECT_EQ(world.table(b).f32(1)[world.location(e).block], 7.0f);
  EXPECT_THROW(world.move(e, c), std::invalid_argument);
  EXPECT_TRUE(world.validate().empty());
}

}  // namespace
}  // namespace strata
