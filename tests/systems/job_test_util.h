#pragma once
// Helpers for the JobValidity tests: fill a job's outputs with a sentinel, break one input at a time, and check
// that validate() and run() refuse it and that no output changed (the ozz-animation JobValidity pattern).
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>

#include "ecs/column_view.h"
#include "ecs/soa_table.h"

namespace strata::test {

inline constexpr float kSentinel = -7777.5f;
inline constexpr std::uint32_t kSentinelBits = 0xdeadbeefu;

// Every row of every column of `field` set to the sentinel's bits (float or integer fields alike).
inline void fill_sentinel(SoaTable& table, std::size_t field) {
  const FieldDesc& f = table.fields()[field];
  for (std::uint32_t c = 0; c < f.width; ++c) {
    if (f.type == ScalarType::F32) {
      for (float& v : table.f32(field, c)) v = kSentinel;
    } else if (f.type == ScalarType::I32) {
      for (std::int32_t& v : table.i32(field, c)) v = static_cast<std::int32_t>(kSentinelBits);
    } else {
      for (std::uint32_t& v : table.u32(field, c)) v = kSentinelBits;
    }
  }
}

// Whether every value of `field` still holds the sentinel.
inline bool holds_sentinel(const SoaTable& table, std::size_t field) {
  const FieldDesc& f = table.fields()[field];
  for (std::uint32_t c = 0; c < f.width; ++c) {
    if (f.type == ScalarType::F32) {
      for (float v : table.f32(field, c))
        if (std::memcmp(&v, &kSentinel, 4) != 0) return false;
    } else if (f.type == ScalarType::I32) {
      for (std::int32_t v : table.i32(field, c))
        if (v != static_cast<std::int32_t>(kSentinelBits)) return false;
    } else {
      for (std::uint32_t v : table.u32(field, c))
        if (v != kSentinelBits) return false;
    }
  }
  return true;
}

// A view with one thing wrong, for the refusal cases.
template <class T>
ColumnView<T> without_base(ColumnView<T> v) {
  v.base = nullptr;
  return v;
}
template <class T>
ColumnView<T> with_components(ColumnView<T> v, std::uint32_t components) {
  v.components = components;
  return v;
}
template <class T>
ColumnView<T> with_count(ColumnView<T> v, std::size_t count) {
  v.count = count;
  return v;
}
template <class T>
ColumnView<T> with_stride(ColumnView<T> v, std::size_t stride) {
  v.stride = stride;
  return v;
}

// Runs the refusal checks for `job`: validate() and run() both false, `untouched()` still true afterwards.
template <class Job, class Untouched>
void expect_refused(const Job& job, const std::string& what, Untouched untouched) {
  EXPECT_FALSE(job.validate()) << what;
  EXPECT_FALSE(job.run()) << what;
  EXPECT_TRUE(untouched()) << what << ": run() wrote an output although it refused";
}

}  // namespace strata::test
