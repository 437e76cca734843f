#pragma once
// SoaTable: structure-of-arrays storage for the entities of one archetype (e.g. all walkers of one rig).
//
// Each entity owns a block of `rows_per_entity` consecutive rows (1 for walker-lane tables, where joints are
// fields; V for per-walker vertex tables). A field is a group of `width` component columns of one scalar type;
// component c of field f is one contiguous, 64-byte-aligned array over all rows, padded to the SIMD width. So
// field "world matrices" of a 25-joint rig has 25*12 components, and the loop over walkers for one joint's one
// matrix entry is a unit-stride stream — the joint-major, walkers-in-lanes layout the IK and FK systems want.
//
// Removal is swap-remove: the last block moves into the hole and the table reports which entity moved, so the
// owner (World) patches that entity's back-pointer. Tables know nothing about handles' validity; World does.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "ecs/aligned_buffer.h"
#include "ecs/entity.h"

namespace strata {

enum class ScalarType : std::uint8_t { F32, I32, U32 };

struct FieldDesc {
  std::string name;
  ScalarType type = ScalarType::F32;
  std::uint32_t width = 1;      // components (e.g. 3 for a position, joints*4 for per-joint quaternions)
  float default_value = 0.0f;   // value of new rows (interpreted as the integer value for I32/U32 fields)
};

class SoaTable {
 public:
  SoaTable(std::string name, std::vector<FieldDesc> fields, std::uint32_t rows_per_entity = 1);

  const std::string& name() const { return name_; }
  std::size_t size() const { return owners_.size(); }             // entities (blocks)
  std::size_t row_count() const { return size() * rows_per_entity_; }
  std::uint32_t rows_per_entity() const { return rows_per_entity_; }
  // Distance in elements between consecutive components of a field; >= row_count(), a multiple of 16.
  std::size_t stride() const { return stride_; }
  std::size_t capacity() const { return capacity_blocks_; }       // blocks before the next reallocation
  const std::vector<FieldDesc>& fields() const { return fields_; }
  std::size_t field_index(std::string_view name) const;           // throws std::out_of_range when absent

  // Appends a block for `owner` (rows set to each field's default) and returns its block index.
  std::uint32_t add(Entity owner);
  // Swap-removes block `block`. Returns the entity whose block moved into `block` (null if it was the last).
  Entity remove(std::uint32_t block);
  Entity owner(std::uint32_t block) const { return owners_[block]; }
  std::span<const Entity> owners() const { return owners_; }
  void reserve(std::size_t blocks);

  // Component column c of field f over all rows (length row_count()). Type must match the field's.
  std::span<float> f32(std::size_t field, std::uint32_t component = 0);
  std::span<const float> f32(std::size_t field, std::uint32_t component = 0) const;
  std::span<std::int32_t> i32(std::size_t field, std::uint32_t component = 0);
  std::span<const std::int32_t> i32(std::size_t field, std::uint32_t component = 0) const;
  std::span<std::uint32_t> u32(std::size_t field, std::uint32_t component = 0);
  std::span<const std::uint32_t> u32(std::size_t field, std::uint32_t component = 0) const;
  // One block's every scalar (every field, component and row of the block, fields in order, then components, then
  // rows), as raw 32-bit words: how a walker's whole state travels to another process (dist/migration.h). A
  // table of the same fields reads it back with write_block. Throws std::out_of_range for a bad block or size.
  std::size_t block_scalars() const;
  void read_block(std::uint32_t block, std::span<std::uint32_t> out) const;
  void write_block(std::uint32_t block, std::span<const std::uint32_t> in);
  // Base of a whole float field: component c starts at base + c * stride(). For kernels that walk components.
  float* f32_base(std::size_t field);
  const float* f32_base(std::size_t field) const;

 private:
  void check(std::size_t field, std::uint32_t component, ScalarType type) const;
  void grow(std::size_t min_blocks);
  std::uint32_t* raw(std::size_t field, std::uint32_t component);
  const std::uint32_t* raw(std::size_t field, std::uint32_t component) const;

  std::string name_;
  std::vector<FieldDesc> fields_;
  std::uint32_t rows_per_entity_;
  std::size_t capacity_blocks_ = 0;
  std::size_t stride_ = 0;
  // One buffer per field holding width * stride_ 32-bit scalars; floats and ints share the storage type.
  std::vector<AlignedBuffer<std::uint32_t>> storage_;
  std::vector<Entity> owners_;  // back-pointers: block -> entity
};

}  // namespace strata
