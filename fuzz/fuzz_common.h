#pragma once
// Shared by the libFuzzer targets (one per loader, fuzz/fuzz_<loader>.cpp). Each target feeds the bytes to the
// loader's from-memory entry point and accepts exactly one outcome besides success: a LoadError whose message is
// one line naming the source. Any other exception escapes and libFuzzer reports it as a crash, which is the point:
// the bad-input contract (docs/reliability.md) allows nothing else.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "io/load_error.h"

namespace strata::fuzz {

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Splits multi-file inputs (MakeHuman's three files, the two binding tables) at NUL bytes, which none of those
// text formats contains; missing parts are empty.
inline std::vector<std::string_view> split_parts(std::string_view text, std::size_t parts) {
  std::vector<std::string_view> out;
  while (out.size() + 1 < parts) {
    const std::size_t nul = text.find('\0');
    if (nul == std::string_view::npos) break;
    out.push_back(text.substr(0, nul));
    text.remove_prefix(nul + 1);
  }
  out.push_back(text);
  out.resize(parts);
  return out;
}

// The error contract: one line, naming the source.
inline void check_message(const LoadError& e, std::string_view source) {
  const std::string_view message = e.what();
  if (message.find('\n') != std::string_view::npos || message.find(source) == std::string_view::npos) {
    std::fprintf(stderr, "bad LoadError message (must be one line naming '%.*s'): %s\n",
                 static_cast<int>(source.size()), source.data(), e.what());
    std::abort();
  }
}

}  // namespace strata::fuzz
