// libFuzzer target: the MakeHuman importer (io/makehuman.h). Input: base.obj, default.mhskel and
// default_weights.mhw joined by NUL bytes (fuzz/seeds/makehuman/ has a small valid trio).
#include "fuzz/fuzz_common.h"
#include "io/makehuman.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto parts = strata::fuzz::split_parts(strata::fuzz::as_text(data, size), 3);
  try {
    (void)strata::load_makehuman_text(parts[0], parts[1], parts[2], "fuzz_mh");
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz_mh");
  }
  return 0;
}
