#pragma once
// AlignedBuffer: a 64-byte-aligned, zero-initialised array of trivially copyable T whose capacity is a multiple
// of kSimdLaneFloats elements, so SIMD kernels can always process whole vectors (the padding is readable and
// writable; its content is unspecified but finite: it starts zeroed and rows moved there by swap-remove stay
// finite). 64 bytes = one cache line = one AVX-512 vector, a superset of the AVX2/SSE needs.
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <new>
#include <span>
#include <type_traits>
#include <utility>

namespace strata {

inline constexpr std::size_t kColumnAlignment = 64;
inline constexpr std::size_t kSimdLaneFloats = kColumnAlignment / sizeof(float);  // 16

constexpr std::size_t pad_to_lanes(std::size_t n) {
  return (n + kSimdLaneFloats - 1) / kSimdLaneFloats * kSimdLaneFloats;
}

template <class T>
class AlignedBuffer {
  static_assert(std::is_trivially_copyable_v<T> && sizeof(T) == 4, "columns hold 32-bit scalars");

 public:
  AlignedBuffer() = default;
  explicit AlignedBuffer(std::size_t count) { reset(count); }
  AlignedBuffer(const AlignedBuffer& other) : AlignedBuffer(other.size_) {
    if (size_) std::memcpy(data_, other.data_, size_ * sizeof(T));
  }
  AlignedBuffer& operator=(const AlignedBuffer& other) {
    if (this != &other) {
      AlignedBuffer copy(other);
      swap(copy);
    }
    return *this;
  }
  AlignedBuffer(AlignedBuffer&& other) noexcept { swap(other); }
  AlignedBuffer& operator=(AlignedBuffer&& other) noexcept {
    swap(other);
    return *this;
  }
  ~AlignedBuffer() { std::free(data_); }

  // Reallocates to hold `count` elements rounded up to whole SIMD vectors; contents are zeroed.
  void reset(std::size_t count) {
    std::free(data_);
    data_ = nullptr;
    size_ = pad_to_lanes(count);
    if (size_ == 0) return;
    data_ = static_cast<T*>(std::aligned_alloc(kColumnAlignment, size_ * sizeof(T)));
    if (!data_) throw std::bad_alloc();
    std::memset(data_, 0, size_ * sizeof(T));
  }

  T* data() { return data_; }
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }  // padded element count
  std::span<T> span() { return {data_, size_}; }
  std::span<const T> span() const { return {data_, size_}; }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }

  void swap(AlignedBuffer& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
  }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace strata
