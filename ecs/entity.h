#pragma once
// Entity handles: a 1-based slot index plus a generation, 8 bytes, trivially copyable. A value-initialised
// Entity{} is the null handle, so "no entity" needs no sentinel constant. A destroyed entity's slot is reused
// with the next generation, which is how stale handles are told apart (EntityPool::alive).
#include <cstdint>
#include <functional>

namespace strata {

struct Entity {
  std::uint32_t index = 0;       // slot + 1; 0 means null
  std::uint32_t generation = 0;  // bumped each time the slot is freed

  constexpr bool is_null() const { return index == 0; }
  constexpr explicit operator bool() const { return index != 0; }
  friend constexpr bool operator==(Entity, Entity) = default;
};
static_assert(sizeof(Entity) == 8, "handles are passed by value and stored in columns; keep them 8 bytes");

}  // namespace strata

template <>
struct std::hash<strata::Entity> {
  std::size_t operator()(strata::Entity e) const noexcept {
    return std::hash<std::uint64_t>{}((std::uint64_t(e.generation) << 32) | e.index);
  }
};
