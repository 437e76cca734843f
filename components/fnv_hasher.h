#pragma once
// FnvHasher: 64-bit FNV-1a over bytes, the key of every on-disk cache (the body, the centres of rotation, the
// impostor atlas): a file is reused only when the hash of everything it was built from matches. Not
// cryptographic; a collision costs a wrong cache hit, which the keyed inputs make vanishingly unlikely.
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace strata {

struct FnvHasher {
  std::uint64_t h = 1469598103934665603ull;
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  }
  template <class T>
  void value(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes(&v, sizeof v);
  }
  // The element count, then the elements' bytes.
  template <class T>
  void vector(const std::vector<T>& v) {
    value(v.size());
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
};

}  // namespace strata
