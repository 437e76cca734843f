// libFuzzer target: the binding tables (rig/binding.h): the part -> joint table and the overrides file, joined by
// a NUL byte.
#include "fuzz/fuzz_common.h"
#include "rig/binding.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto parts = strata::fuzz::split_parts(strata::fuzz::as_text(data, size), 2);
  try {
    (void)strata::load_binding_tables(parts[0], parts[1], "fuzz_parts.json", "fuzz_overrides.json");
  } catch (const strata::LoadError& e) {
    const std::string_view m = e.what();
    if (m.find('\n') != std::string_view::npos ||
        (m.find("fuzz_parts.json") == std::string_view::npos && m.find("fuzz_overrides.json") == std::string_view::npos)) {
      std::fprintf(stderr, "bad LoadError message: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}
