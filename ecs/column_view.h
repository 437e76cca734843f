#pragma once
// ColumnView: a non-owning view of one field of a SoaTable (or of any component-major block laid out the same
// way): `components` columns of `count` rows each, column c starting at base + c * stride. It is what the
// systems' job structs (systems/*.h) take as inputs and outputs: a job's input is a ColumnView<const T>, its
// output a ColumnView<T>, so what a system reads and writes is in its member types.
//
// Why not std::span per field: a field is many columns (25 joints x 12 matrix entries), and the kernels walk
// them by base + c * stride; a span of the whole field would hide the stride, and a span per column would make
// a job carry hundreds of spans. Why not a view into the SoaTable itself: the jobs would then depend on the
// table's field numbering and could grow it; a view is three numbers and a pointer, and a test can point one at
// a plain array.
//
// Validity (what jobs' validate() checks through fits()): `count` rows, `components` as the job expects,
// stride >= count, and a non-null base unless the view is empty (an empty table has no storage yet).
// Views stay valid until the table grows, shrinks or is destroyed: make them per frame, right before the run.
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "ecs/soa_table.h"

namespace strata {

template <class T>
struct ColumnView {
  T* base = nullptr;             // column 0, row 0
  std::uint32_t components = 0;  // columns in the view (the field's width)
  std::size_t stride = 0;        // elements from one column to the next; >= count
  std::size_t count = 0;         // rows (walkers)

  T* component(std::uint32_t c) const { return base + static_cast<std::size_t>(c) * stride; }
  T& at(std::uint32_t c, std::size_t row) const { return base[static_cast<std::size_t>(c) * stride + row]; }

  // True when the view has `rows` rows and `width` columns, a sane stride and storage behind it.
  bool fits(std::size_t rows, std::uint32_t width) const {
    return count == rows && components == width && stride >= count && (base != nullptr || count == 0);
  }
  // Whether the view overlaps `other` in memory (any column of one with any column of the other). Jobs refuse
  // aliasing between an input and an output they would read after writing.
  template <class U>
  bool overlaps(const ColumnView<U>& other) const {
    if (!base || !other.base || components == 0 || other.components == 0) return false;
    const auto* a0 = reinterpret_cast<const unsigned char*>(base);
    const auto* a1 = reinterpret_cast<const unsigned char*>(component(components - 1) + count);
    const auto* b0 = reinterpret_cast<const unsigned char*>(other.base);
    const auto* b1 = reinterpret_cast<const unsigned char*>(other.component(other.components - 1) + other.count);
    return a0 < b1 && b0 < a1;
  }

  // Rows [first, first + n) of every column: same stride, base moved. For running a job on part of a table.
  ColumnView rows(std::size_t first, std::size_t n) const { return {base ? base + first : base, components, stride, n}; }

  // Columns [first, first + n) of the view: for a job that reads one component of a field and writes another
  // (the clock's time is written, its rate only read), so each gets the constness it needs.
  ColumnView columns(std::uint32_t first, std::uint32_t n) const {
    return {base ? component(first) : base, n, stride, count};
  }

  // A mutable view converts to a read-only one (an output of one job is the input of the next).
  operator ColumnView<const T>() const
    requires(!std::is_const_v<T>)
  {
    return {base, components, stride, count};
  }
};

// Views of field `field` of `table`, all rows. The field's scalar type must match (std::invalid_argument
// otherwise, from SoaTable); a table without rows gives an empty view (its base may be null).
inline ColumnView<float> f32_view(SoaTable& table, std::size_t field) {
  return {table.f32_base(field), table.fields().at(field).width, table.stride(),
          table.row_count()};
}
inline ColumnView<const float> f32_view(const SoaTable& table, std::size_t field) {
  return {table.f32_base(field), table.fields().at(field).width, table.stride(),
          table.row_count()};
}
inline ColumnView<std::int32_t> i32_view(SoaTable& table, std::size_t field) {
  return {table.i32(field).data(), table.fields().at(field).width, table.stride(),
          table.row_count()};
}
inline ColumnView<const std::int32_t> i32_view(const SoaTable& table, std::size_t field) {
  return {table.i32(field).data(), table.fields().at(field).width, table.stride(),
          table.row_count()};
}
inline ColumnView<std::uint32_t> u32_view(SoaTable& table, std::size_t field) {
  return {table.u32(field).data(), table.fields().at(field).width, table.stride(),
          table.row_count()};
}
inline ColumnView<const std::uint32_t> u32_view(const SoaTable& table, std::size_t field) {
  return {table.u32(field).data(), table.fields().at(field).width, table.stride(),
          table.row_count()};
}

}  // namespace strata
