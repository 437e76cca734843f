// libFuzzer target: the packed MakeHuman source reader (io/makehuman_pack.h), whose shipped instance the default
// body is derived from. fuzz/seeds/makehuman_pack/ has a valid tetrahedron; the corpus adds data/makehuman_body.bin.
#include "fuzz/fuzz_common.h"
#include "io/makehuman_pack.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)strata::unpack_makehuman_source(strata::fuzz::as_text(data, size), "fuzz_pack");
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz_pack");
  }
  return 0;
}
