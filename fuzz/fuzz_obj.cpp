// libFuzzer target: Wavefront OBJ (io/obj.h), with the vertex correspondence requested.
#include "fuzz/fuzz_common.h"
#include "io/obj.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    strata::ObjSource source;
    (void)strata::load_obj_text(strata::fuzz::as_text(data, size), "fuzz.obj", {}, &source);
  } catch (const strata::LoadError& e) {
    strata::fuzz::check_message(e, "fuzz.obj");
  }
  return 0;
}
