#include "ecs/soa_table.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <stdexcept>

namespace strata {
namespace {

std::uint32_t default_bits(const FieldDesc& field) {
  switch (field.type) {
    case ScalarType::F32:
      return std::bit_cast<std::uint32_t>(field.default_value);
    case ScalarType::I32:
      return std::bit_cast<std::uint32_t>(static_cast<std::int32_t>(field.default_value));
    case ScalarType::U32:
      return static_cast<std::uint32_t>(field.default_value);
  }
  return 0;
}

}  // namespace

SoaTable::SoaTable(std::string name, std::vector<FieldDesc> fields, std::uint32_t rows_per_entity)
    : name_(std::move(name)), fields_(std::move(fields)), rows_per_entity_(rows_per_entity) {
  if (rows_per_entity_ == 0) throw std::invalid_argument("SoaTable '" + name_ + "': rows_per_entity must be >= 1");
  for (std::size_t i = 0; i < fields_.size(); ++i) {
    if (fields_[i].width == 0)
      throw std::invalid_argument("SoaTable '" + name_ + "': field '" + fields_[i].name + "' has width 0");
    for (std::size_t k = 0; k < i; ++k)
      if (fields_[k].name == fields_[i].name)
        throw std::invalid_argument("SoaTable '" + name_ + "': duplicate field '" + fields_[i].name + "'");
  }
  storage_.resize(fields_.size());
}

std::size_t SoaTable::field_index(std::string_view name) const {
  for (std::size_t i = 0; i < fields_.size(); ++i)
    if (fields_[i].name == name) return i;
  throw std::out_of_range("SoaTable '" + name_ + "': no field '" + std::string(name) + "'");
}

void SoaTable::reserve(std::size_t blocks) {
  if (blocks > capacity_blocks_) grow(blocks);
}

// Geometric growth; every column of every field moves to a new stride at once, so component c of field f is
// always at base + c * stride. The alternative, one allocation per component, would keep old pointers stable on
// growth but costs widths*fields allocations per table (a 25-joint rig has over 800 components).
void SoaTable::grow(std::size_t min_blocks) {
  std::size_t blocks = std::max<std::size_t>({min_blocks, capacity_blocks_ * 2, 16});
  std::size_t new_stride = pad_to_lanes(blocks * rows_per_entity_);
  std::size_t rows = row_count();
  for (std::size_t f = 0; f < fields_.size(); ++f) {
    AlignedBuffer<std::uint32_t> bigger(std::size_t(fields_[f].width) * new_stride);
    if (rows > 0)
      for (std::uint32_t c = 0; c < fields_[f].width; ++c)
        std::memcpy(bigger.data() + c * new_stride, storage_[f].data() + c * stride_, rows * sizeof(std::uint32_t));
    storage_[f] = std::move(bigger);
  }
  capacity_blocks_ = blocks;
  stride_ = new_stride;
  owners_.reserve(blocks);
}

std::uint32_t SoaTable::add(Entity owner) {
  if (size() == capacity_blocks_) grow(size() + 1);
  std::size_t first = row_count();
  for (std::size_t f = 0; f < fields_.size(); ++f) {
    std::uint32_t bits = default_bits(fields_[f]);
    for (std::uint32_t c = 0; c < fields_[f].width; ++c) {
      std::uint32_t* column = storage_[f].data() + c * stride_;
      std::fill(column + first, column + first + rows_per_entity_, bits);
    }
  }
  owners_.push_back(owner);
  return static_cast<std::uint32_t>(owners_.size() - 1);
}

Entity SoaTable::remove(std::uint32_t block) {
  if (block >= size()) throw std::out_of_range("SoaTable '" + name_ + "': remove of block past the end");
  std::uint32_t last = static_cast<std::uint32_t>(size() - 1);
  Entity moved{};
  if (block != last) {
    std::size_t dst = std::size_t(block) * rows_per_entity_;
    std::size_t src = std::size_t(last) * rows_per_entity_;
    for (std::size_t f = 0; f < fields_.size(); ++f)
      for (std::uint32_t c = 0; c < fields_[f].width; ++c) {
        std::uint32_t* column = storage_[f].data() + c * stride_;
        std::memcpy(column + dst, column + src, rows_per_entity_ * sizeof(std::uint32_t));
      }
    owners_[block] = owners_[last];
    moved = owners_[block];
  }
  owners_.pop_back();
  return moved;
}

void SoaTable::check(std::size_t field, std::uint32_t component, ScalarType type) const {
  if (field >= fields_.size()) throw std::out_of_range("SoaTable '" + name_ + "': field index out of range");
  if (component >= fields_[field].width)
    throw std::out_of_range("SoaTable '" + name_ + "': component out of range in field '" + fields_[field].name + "'");
  if (fields_[field].type != type)
    throw std::invalid_argument("SoaTable '" + name_ + "': field '" + fields_[field].name + "' accessed as wrong type");
}

std::size_t SoaTable::block_scalars() const {
  std::size_t n = 0;
  for (const FieldDesc& f : fields_) n += std::size_t(f.width) * rows_per_entity_;
  return n;
}

void SoaTable::read_block(std::uint32_t block, std::span<std::uint32_t> out) const {
  if (block >= size() || out.size() != block_scalars())
    throw std::out_of_range("SoaTable '" + name_ + "': read_block outside the table or of the wrong size");
  std::size_t k = 0;
  const std::size_t row0 = std::size_t(block) * rows_per_entity_;
  for (std::size_t f = 0; f < fields_.size(); ++f)
    for (std::uint32_t c = 0; c < fields_[f].width; ++c) {
      const std::uint32_t* column = raw(f, c) + row0;
      for (std::uint32_t r = 0; r < rows_per_entity_; ++r) out[k++] = column[r];
    }
}

void SoaTable::write_block(std::uint32_t block, std::span<const std::uint32_t> in) {
  if (block >= size() || in.size() != block_scalars())
    throw std::out_of_range("SoaTable '" + name_ + "': write_block outside the table or of the wrong size");
  std::size_t k = 0;
  const std::size_t row0 = std::size_t(block) * rows_per_entity_;
  for (std::size_t f = 0; f < fields_.size(); ++f)
    for (std::uint32_t c = 0; c < fields_[f].width; ++c) {
      std::uint32_t* column = raw(f, c) + row0;
      for (std::uint32_t r = 0; r < rows_per_entity_; ++r) column[r] = in[k++];
    }
}

std::uint32_t* SoaTable::raw(std::size_t field, std::uint32_t component) {
  return storage_[field].data() + std::size_t(component) * stride_;
}
const std::uint32_t* SoaTable::raw(std::size_t field, std::uint32_t component) const {
  return storage_[field].data() + std::size_t(component) * stride_;
}

std::span<float> SoaTable::f32(std::size_t field, std::uint32_t component) {
  check(field, component, ScalarType::F32);
  return {reinterpret_cast<float*>(raw(field, component)), row_count()};
}
std::span<const float> SoaTable::f32(std::size_t field, std::uint32_t component) const {
  check(field, component, ScalarType::F32);
  return {reinterpret_cast<const float*>(raw(field, component)), row_count()};
}
std::span<std::int32_t> SoaTable::i32(std::size_t field, std::uint32_t component) {
  check(field, component, ScalarType::I32);
  return {reinterpret_cast<std::int32_t*>(raw(field, component)), row_count()};
}
std::span<const std::int32_t> SoaTable::i32(std::size_t field, std::uint32_t component) const {
  check(field, component, ScalarType::I32);
  return {reinterpret_cast<const std::int32_t*>(raw(field, component)), row_count()};
}
std::span<std::uint32_t> SoaTable::u32(std::size_t field, std::uint32_t component) {
  check(field, component, ScalarType::U32);
  return {raw(field, component), row_count()};
}
std::span<const std::uint32_t> SoaTable::u32(std::size_t field, std::uint32_t component) const {
  check(field, component, ScalarType::U32);
  return {raw(field, component), row_count()};
}
float* SoaTable::f32_base(std::size_t field) {
  check(field, 0, ScalarType::F32);
  return reinterpret_cast<float*>(raw(field, 0));
}
const float* SoaTable::f32_base(std::size_t field) const {
  check(field, 0, ScalarType::F32);
  return reinterpret_cast<const float*>(raw(field, 0));
}

}  // namespace strata
